"""A wheeled base's spec against its URDF (``robots/wheel_checks.py``): the wheel convention (base +x forward, left
wheels on +y, axles along +y), wheels that can drive the base, a radius that fits the wheels, and values derived from
the URDF named as derived in the errors about them."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from clutter_gym.assets import asset_path
from clutter_gym.robots.wheeled import wheeled_base_from_spec
from clutter_gym.sim import pybullet_data_file

DIFFBOT = asset_path("robots/diffbot.urdf")
BASE = {"kind": "diff_drive", "urdf": str(DIFFBOT), "left_wheels": ["left_wheel_joint"],
        "right_wheels": ["right_wheel_joint"]}
R2D2 = {"kind": "diff_drive", "urdf": str(pybullet_data_file("r2d2.urdf")),
        "left_wheels": ["left_front_wheel_joint", "left_back_wheel_joint"],
        "right_wheels": ["right_front_wheel_joint", "right_back_wheel_joint"],
        "mounts": {"lidar_link": {"parent": "base_link", "xyz": [0.0, 0.0, 0.3]}, "imu_link": {"parent": "base_link"}}}


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # prepared URDFs land here, not in ~/.cache


def diffbot_with(tmp_path: Path, *edits: tuple[str, str]) -> str:
    """The diffbot's URDF with each ``(old, new)`` replaced (every ``old`` must be in it), written into tmp_path."""
    text = DIFFBOT.read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "edited.urdf"
    path.write_text(text)
    return str(path)


def refused(spec: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        wheeled_base_from_spec(spec, "spec")


# -- the convention ---------------------------------------------------------------------------------------------

def test_r2d2_which_drives_along_y_is_refused_naming_the_axis_it_drives_along():
    """pybullet_data's r2d2 has its axles along x, so it drives along y. Before: it was refused for a
    ``wheel_separation`` of 0.0 the user never wrote, and with ``wheel_separation: 0.44`` set by hand a forward
    command moved it 0.95 m sideways while its ``velocity`` read about 0."""
    cause = (r"spec: wheel joint 'left_front_wheel_joint' of .*r2d2.urdf turns about \(1, 0, 4.63e-05\) in the base "
             r"frame; the axles lie along x, so the base drives along y: clutter-gym drives a base along its \+x "
             r"with its wheels' axles along \+y \(REP 103, docs/robots.md\); turn the URDF's base so \+x points "
             r"forward$")
    refused(R2D2, cause)
    refused({**R2D2, "wheel_separation": 0.44}, cause)


@pytest.mark.parametrize("sides, message", [
    ({"left_wheels": ["right_wheel_joint"], "right_wheels": ["left_wheel_joint"]},
     r"wheel joints \['right_wheel_joint', 'left_wheel_joint'\] of .*diffbot.urdf sit at y = \[-0.145, 0.145\] in "
     r"the base frame, on the wrong side or the centreline: the lists are swapped: with \+x forward, the left side "
     r"is \+y; swap left_wheels and right_wheels"),
    ({"right_wheels": ["left_wheel_joint"]},
     r"left_wheels and right_wheels both name \['left_wheel_joint'\]; each wheel drives one side"),
    ({"left_wheels": ["left_wheel_joint", "right_wheel_joint"], "right_wheels": ["right_wheel_joint"]},
     r"both name \['right_wheel_joint'\]"),
    ({"left_wheels": ["left_wheel_joint", "left_wheel_joint"]}, r"left_wheels names \['left_wheel_joint'\] more "
                                                                r"than once"),
])
def test_swapped_or_shared_wheel_lists_are_named_as_such(sides, message):
    """Before: each was blamed on a ``wheel_separation`` (-0.29, 0.0, ...) the user never wrote."""
    refused({**BASE, **sides}, message)


@pytest.mark.parametrize("axis, message", [
    ("0 0 1", r"turns about \(0, 0, 1\) in the base frame; its axle stands upright, so it cannot roll"),
    ("0 -1 0", r"turns about \(0, -1, 0\) in the base frame; a positive wheel speed rolls it backward: .*flip the "
               r"joint's <axis>, or, if the base's front is -x, turn the URDF's base so \+x points forward"),
    ("1 0 0", r"turns about \(1, 0, 0\) in the base frame; the axles lie along x, so the base drives along y"),
    ("0.2 1 0", r"turns about \(0.196, 0.981, 0\) .*the wheel is toed in or out by more than 5 degrees"),
])
def test_a_wheel_axle_off_the_lateral_axis_is_refused(tmp_path, axis, message):
    """Before: a vertical wheel axis was accepted and the base barely moved."""
    urdf = diffbot_with(tmp_path, ('<axis xyz="0 1 0"/>', f'<axis xyz="{axis}"/>'))
    refused({**BASE, "urdf": urdf}, rf"spec: wheel joint 'left_wheel_joint' of .*edited.urdf {message}")


def test_a_wheel_axle_a_little_off_is_taken(tmp_path):
    """Within :data:`AXLE_TOLERANCE` (a camber of 3 degrees here) the base is read as before."""
    urdf = diffbot_with(tmp_path, ('<axis xyz="0 1 0"/>', '<axis xyz="0 1 0.0524"/>'))
    assert wheeled_base_from_spec({**BASE, "urdf": urdf}, "spec").wheel_separation == pytest.approx(0.29)


# -- wheels that can drive the base ------------------------------------------------------------------------------

@pytest.mark.parametrize("edits, message", [
    ([('<origin xyz="0.12 0 -0.03"/>', '<origin xyz="0.12 0 -0.04"/>')],
     r"link 'front_caster' of .*edited.urdf reaches 10.0 mm below the wheels' lowest points \(z = -0.0600 m against "
     r"-0.0500 m in the base frame, joints at zero\): the base would rest on it and its wheels would not grip"),
    ([('<origin xyz="0 0 0.025"/>\n      <geometry><cylinder radius="0.17" length="0.12"/></geometry>\n    '
       '</collision>', '<origin xyz="0 0 -0.01"/>\n      <geometry><cylinder radius="0.17" length="0.12"/>'
                       '</geometry>\n    </collision>')],
     r"link 'base_link' of .*reaches 20.0 mm below the wheels' lowest points"),
    ([('type="continuous"', 'type="prismatic"')], r"wheel joint 'left_wheel_joint' of .* is prismatic; a wheel turns"),
    ([('type="continuous"', 'type="revolute"'), ('<limit effort="1.5"', '<limit lower="-1" upper="1" effort="1.5"')],
     r"wheel joint 'left_wheel_joint' of .* is revolute with <limit lower=-1 upper=1>, which pybullet stops it at; "
     r"a wheel turns freely: make it continuous"),
    ([('<mass value="2.5"/>', '<mass value="0"/>')],
     r"root link 'base_link' of .* has <mass value=0>: pybullet holds a body whose base weighs nothing still"),
    ([('<mass value="0.2"/>', '<mass value="0"/>')],
     r"wheel link 'left_wheel' of .* has <mass value=0>: wheels that weigh nothing do not drive the base"),
    ([('<collision>\n      <origin rpy="1.5707963 0 0"/>\n      <geometry><cylinder radius="0.05" length="0.03"/>'
       '</geometry>\n    </collision>', '')],
     r"wheel link 'left_wheel' of .* has no collision geometry, so it cannot touch the floor"),
])
def test_a_base_that_cannot_drive_as_the_unicycle_model_says_is_refused(tmp_path, edits, message):
    """Before: each was accepted. Casters or a chassis below the wheels, or a zero mass, left the base barely moving
    (the diffbot covers 1.47 m in 60 forward steps)."""
    refused({**BASE, "urdf": diffbot_with(tmp_path, *edits)}, rf"^spec: {message}")


def test_a_revolute_wheel_pybullet_leaves_free_is_taken(tmp_path):
    """pybullet enforces a revolute joint's limits only when lower <= upper; without them the wheel turns freely."""
    urdf = diffbot_with(tmp_path, ('type="continuous"', 'type="revolute"'))
    assert wheeled_base_from_spec({**BASE, "urdf": urdf}, "spec").wheel_radius == 0.05


# -- the wheel radius, and values derived from the URDF ----------------------------------------------------------

def test_a_wheel_radius_far_from_the_wheels_is_refused_naming_both():
    """Before: a spec's ``wheel_radius`` of 6x the URDF's wheel was accepted (every commanded speed 6x too slow)."""
    refused({**BASE, "wheel_radius": 0.3}, r"spec: wheel_radius 0.3 m disagrees with wheel link 'left_wheel' of "
                                           r".*diffbot.urdf, whose collision shape reaches 0.05 m below its axle "
                                           r"\(more than 25% apart\)")
    assert wheeled_base_from_spec({**BASE, "wheel_radius": 0.06}, "spec").wheel_radius == 0.06  # within 25%


def test_a_derived_radius_from_a_cylinder_that_does_not_stand_on_its_rim_is_named_as_derived(tmp_path):
    urdf = diffbot_with(tmp_path, ('<collision>\n      <origin rpy="1.5707963 0 0"/>', '<collision>\n      <origin/>'))
    refused({**BASE, "urdf": urdf}, r"spec: wheel_radius, derived from the wheel links' collision cylinders, is 0.05 "
                                    r"m, but disagrees with wheel link 'left_wheel' of .*edited.urdf, whose collision "
                                    r"shape reaches 0.015 m below its axle .*turn its cylinder so its axis is the "
                                    r"axle, or give wheel_radius")


def test_a_derived_track_out_of_range_is_named_as_derived(tmp_path):
    urdf = diffbot_with(tmp_path, ('<origin xyz="0 0.145 0"/>', '<origin xyz="0 0.004 0"/>'),
                        ('<origin xyz="0 -0.145 0"/>', '<origin xyz="0 -0.004 0"/>'))
    refused({**BASE, "urdf": urdf}, r"spec: wheel_separation was not given, and reading it from the wheel joints' "
                                    r"positions in .*edited.urdf \(the left wheels' mean y less the right's\) gives "
                                    r"0.008, outside \[0.01, 5\]: give wheel_separation in the spec")


@pytest.mark.parametrize("value, message", [
    (True, r"wheel_radius must be a number in \[0.005, 2\], got True \(text and true/false are not numbers\)"),
    ("0.05", r"wheel_radius must be a number in \[0.005, 2\], got '0.05' \(text and true/false are not numbers\)"),
])
def test_booleans_and_numeric_text_are_not_numbers(value, message):
    """Before: ``wheel_radius: true`` was a 1 m wheel and ``"0.05"`` was 0.05."""
    refused({**BASE, "wheel_radius": value}, re.escape("spec: ") + message)


def test_exponent_notation_pyyaml_leaves_as_text_is_a_number():
    """PyYAML (YAML 1.1) reads ``5e-2`` and ``5.0e-2`` as text; YAML 1.2 and the spec take them as numbers."""
    for text in ("5e-2", "5.0e-2"):
        assert wheeled_base_from_spec({**BASE, "wheel_radius": text}, "spec").wheel_radius == 0.05


def test_the_registered_bases_fit_the_convention():
    from clutter_gym.robots.registry import resolve_robot

    husky = resolve_robot("husky", "diff_drive", "test")
    assert husky.wheel_separation == pytest.approx(0.5708) and husky.wheel_radius == pytest.approx(0.17775)
