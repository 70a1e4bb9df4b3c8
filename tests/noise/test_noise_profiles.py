"""Named profiles: traceable values, overrides and clear errors."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from clutter_gym.noise.profiles import (
    NOISE_SECTIONS,
    PROFILE_NAMES,
    TIMED_SENSORS,
    NoiseProfile,
    profile_sources,
    profile_table_markdown,
    resolve_noise,
    sensor_sections,
)
from clutter_gym.sensors.lidar import LidarConfig

NOISE_DOC = Path(__file__).resolve().parents[2] / "docs" / "noise.md"
REFERENCE_DOC = NOISE_DOC.parent / "sensor-noise-reference.md"


def test_the_four_profiles_exist_and_none_is_clean():
    assert PROFILE_NAMES == ("none", "nominal", "low-cost", "harsh")
    clean = resolve_noise("none")
    assert clean == NoiseProfile()
    for section in NOISE_SECTIONS:
        assert getattr(clean, section).is_clean
    assert resolve_noise(None) == clean


@pytest.mark.parametrize("name", ["nominal", "low-cost", "harsh"])
def test_every_profile_value_cites_a_source(name):
    sources = profile_sources(name)
    assert sources, name
    for section, values in sources.items():
        assert section in NOISE_SECTIONS or section in TIMED_SENSORS or section in sensor_sections(), section
        for key, (value, source) in values.items():
            assert isinstance(value, (int, float)) and isinstance(source, str) and source.strip(), (section, key)
            # a reference-table row (L/T/D/I/O + number) or an explicit UNSOURCED
            assert "UNSOURCED" in source or re.search(r"\b[LTDIO]\d+", source), (section, key, source)
    resolve_noise(name)  # every value is in its allowed range


def test_profiles_grow_worse_in_order():
    nominal, low, harsh = (resolve_noise(n) for n in ("nominal", "low-cost", "harsh"))
    for field in ("range_sigma_frac", "dropout_prob", "spurious_prob"):
        assert getattr(nominal.lidar, field) <= getattr(low.lidar, field) <= getattr(harsh.lidar, field)
    for field in ("gyro_noise_density", "accel_noise_density", "gyro_turn_on_sigma", "scale_sigma"):
        assert getattr(nominal.imu, field) <= getattr(low.imu, field) <= getattr(harsh.imu, field)
    assert nominal.camera_depth.hole_prob <= low.camera_depth.hole_prob <= harsh.camera_depth.hole_prob


def test_harsh_lidar_window_is_the_default_scan_window():
    # one fact, the TurtleBot3 LDS-01's range window (L8): profiles.yaml cites it, LidarConfig defaults to it
    harsh, default = resolve_noise("harsh").lidar, LidarConfig()
    assert (harsh.min_range, harsh.max_range) == (default.min_range, default.max_range)


def test_override_changes_one_parameter_and_keeps_the_rest():
    base = resolve_noise("nominal")
    changed = resolve_noise({"profile": "nominal", "lidar": {"range_sigma": 0.02, "latency_steps": 3}})
    assert changed.lidar.range_sigma == 0.02
    assert changed.timing["lidar"].latency_steps == 3
    assert changed.lidar.dropout_prob == base.lidar.dropout_prob
    assert changed.imu == base.imu and changed.timing["imu"] == base.timing["imu"]
    assert resolve_noise({"imu": {"gyro_noise_density": 1e-3}}).lidar.is_clean  # starts from "none"


def test_to_dict_round_trips():
    profile = resolve_noise("harsh")
    assert resolve_noise(profile.to_dict()) == profile


@pytest.mark.parametrize(
    "spec, pattern",
    [
        ("noisy", r"noise profile must be one of \('none', 'nominal', 'low-cost', 'harsh'\)"),
        ({"profile": "nominal", "sonar": {}}, r"unknown noise sections \['sonar'\]"),
        ({"lidar": {"sigma": 0.1}}, r"unknown lidar noise parameters \['sigma'\]; allowed: \['range_sigma'"),
        ({"lidar": {"range_sigma": 2.0}}, r"lidar\.range_sigma must be a number in \[0\.0, 1\.0\] m, got 2\.0"),
        ({"imu": {"latency_steps": -1}}, r"imu\.latency_steps must be an integer in \[0, 50\]"),
        ({"camera": {"rate_hz": -5}}, r"camera\.rate_hz must be a number in \[0\.0, 10000\.0\] Hz"),
        ({"camera": {"read_sigma": 1}}, r"noise section 'camera' takes only \['rate_hz', 'latency_steps'\]"),
        ({"action": 0.1}, r"noise\['action'\] must be a mapping"),
        (3, r"noise must be a profile name"),
    ],
)
def test_bad_specs_name_what_is_wrong(spec, pattern):
    with pytest.raises(ValueError, match=pattern):
        resolve_noise(spec)


def test_docs_profile_table_is_the_generated_one():
    """docs/noise.md holds the sections of profiles.yaml; a section a sensor declares is on docs/sensors.md."""
    table = profile_table_markdown((*NOISE_SECTIONS, *TIMED_SENSORS))
    assert table in NOISE_DOC.read_text(encoding="utf-8"), (
        "docs/noise.md's profile table is stale: regenerate it with `clutter-gym profiles`"
    )
    assert "`odometry." not in table and "`odometry.ticks_per_rev`" in profile_table_markdown()


@pytest.mark.parametrize("name", sorted(sensor_sections()))
def test_a_declared_sections_sources_cite_rows_that_exist(name):
    """Each ID a declared section's source cites is a row of the survey or of the section's own references, which
    repeat no survey ID, and the section describes its model."""
    section = sensor_sections()[name]
    survey = set(re.findall(r"^\| ([LTDIO]\d+) \|", REFERENCE_DOC.read_text(encoding="utf-8"), flags=re.M))
    assert survey and not survey & set(section.references), survey & set(section.references)
    for profile, values in section.profiles.items():
        for key, (_, source) in values.items():
            cited = re.findall(r"\b([LTDIO]\d+)\b", source)
            assert cited or "UNSOURCED" in source, (profile, key, source)
            assert set(cited) <= survey | set(section.references), (profile, key, source)
    assert section.model.strip()
