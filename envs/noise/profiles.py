"""Named noise profiles (``profiles.yaml``) and how ``gym.make(..., noise=...)`` resolves them.

``noise`` may be a profile name (``"none"``, ``"nominal"``, ``"low-cost"``, ``"harsh"``), a mapping that starts
from a profile and overrides parameters per section, or a :class:`NoiseProfile`::

    gym.make("ClutterNav-v1", noise={"profile": "nominal", "lidar": {"range_sigma": 0.02, "latency_steps": 1}})

Sections: ``lidar``, ``imu``, ``camera_rgb``, ``camera_depth``, ``camera`` (timing only), ``action`` and
``dynamics``. The sensor sections ``lidar``, ``imu`` and ``camera`` also take the timing keys ``rate_hz`` and
``latency_steps`` (:class:`~clutter_gym.noise.timing.SensorTiming`).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from importlib import resources
from typing import Any

import yaml

from clutter_gym.noise.action import ActionNoise
from clutter_gym.noise.camera import DepthNoise, RgbNoise
from clutter_gym.noise.dynamics import DynamicsNoise
from clutter_gym.noise.imu import ImuNoise
from clutter_gym.noise.lidar import LidarNoise
from clutter_gym.noise.params import NoiseParams
from clutter_gym.noise.timing import SensorTiming

#: Sections of noise parameters, by name.
NOISE_SECTIONS: dict[str, type[NoiseParams]] = {
    "lidar": LidarNoise,
    "imu": ImuNoise,
    "camera_rgb": RgbNoise,
    "camera_depth": DepthNoise,
    "action": ActionNoise,
    "dynamics": DynamicsNoise,
}
#: Sensors with timing; ``camera`` has no noise section of its own (its noise is in camera_rgb / camera_depth).
TIMED_SENSORS = ("lidar", "imu", "camera")
_TIMING_KEYS = tuple(f.name for f in dataclasses.fields(SensorTiming))


@functools.cache
def _timing_class(sensor: str) -> type[SensorTiming]:
    """SensorTiming whose error messages name the sensor (``lidar.rate_hz``)."""
    return type(f"{sensor.capitalize()}Timing", (SensorTiming,), {"section": sensor})


@dataclasses.dataclass(frozen=True)
class NoiseProfile:
    """Everything that makes a simulated episode less ideal than the simulator's ground truth."""

    name: str = "none"
    lidar: LidarNoise = LidarNoise()
    imu: ImuNoise = ImuNoise()
    camera_rgb: RgbNoise = RgbNoise()
    camera_depth: DepthNoise = DepthNoise()
    action: ActionNoise = ActionNoise()
    dynamics: DynamicsNoise = DynamicsNoise()
    timing: Mapping[str, SensorTiming] = dataclasses.field(
        default_factory=lambda: {sensor: _timing_class(sensor)() for sensor in TIMED_SENSORS}
    )

    def to_dict(self) -> dict[str, Any]:
        """Plain values, in the override format (every parameter, clean ones included)."""
        out: dict[str, Any] = {"profile": self.name}
        for section in NOISE_SECTIONS:
            out[section] = dataclasses.asdict(getattr(self, section))
        for sensor in TIMED_SENSORS:
            out.setdefault(sensor, {}).update(dataclasses.asdict(self.timing[sensor]))
        return out


@functools.cache
def _profile_file() -> dict[str, dict[str, Any]]:
    text = resources.files("clutter_gym.noise").joinpath("profiles.yaml").read_text(encoding="utf-8")
    return yaml.safe_load(text)


PROFILE_NAMES: tuple[str, ...] = tuple(_profile_file())


def profile_sources(name: str) -> dict[str, dict[str, tuple[float, str]]]:
    """``{section: {parameter: (value, source)}}`` of a named profile as written in profiles.yaml."""
    if name not in PROFILE_NAMES:
        raise ValueError(f"noise profile must be one of {PROFILE_NAMES}, got {name!r}")
    return {
        section: {key: (entry[0], entry[1]) for key, entry in values.items()}
        for section, values in _profile_file()[name].items()
        if section != "description"
    }


def profile_description(name: str) -> str:
    """The one-line description of a named profile."""
    if name not in PROFILE_NAMES:
        raise ValueError(f"noise profile must be one of {PROFILE_NAMES}, got {name!r}")
    return _profile_file()[name]["description"]


def resolve_noise(spec: str | Mapping[str, Any] | NoiseProfile | None) -> NoiseProfile:
    """The profile that ``gym.make(..., noise=spec)`` asks for (None = "none").

    Raises:
        ValueError: an unknown profile, section or parameter, or a value out of its range; the message names it.
    """
    if isinstance(spec, NoiseProfile):
        return spec
    if spec is None:
        spec = "none"
    if isinstance(spec, str):
        spec = {"profile": spec}
    if not isinstance(spec, Mapping):
        raise ValueError(
            f"noise must be a profile name from {PROFILE_NAMES}, a mapping or a NoiseProfile, got {spec!r}"
        )
    name = spec.get("profile", "none")
    base = {section: {k: v for k, (v, _) in values.items()} for section, values in profile_sources(name).items()}
    overrides = {key: value for key, value in spec.items() if key != "profile"}
    allowed = sorted({*NOISE_SECTIONS, *TIMED_SENSORS})
    unknown = sorted(set(overrides) - set(allowed))
    if unknown:
        raise ValueError(f"unknown noise sections {unknown}; allowed: {['profile', *allowed]}")
    for section, values in overrides.items():
        if not isinstance(values, Mapping):
            raise ValueError(f"noise[{section!r}] must be a mapping of parameters, got {values!r}")
        base[section] = {**base.get(section, {}), **values}
    return _build(name, base)


def _build(name: str, values: Mapping[str, Mapping[str, Any]]) -> NoiseProfile:
    sections: dict[str, Any] = {}
    timing: dict[str, SensorTiming] = {}
    for section in sorted({*NOISE_SECTIONS, *TIMED_SENSORS}):
        given = dict(values.get(section, {}))
        if section in TIMED_SENSORS:
            timing[section] = _timing_class(section).from_dict({k: given.pop(k) for k in _TIMING_KEYS if k in given})
        if section in NOISE_SECTIONS:
            sections[section] = NOISE_SECTIONS[section].from_dict(given)
        elif given:
            raise ValueError(f"noise section {section!r} takes only {list(_TIMING_KEYS)}, got {sorted(given)}")
    return NoiseProfile(name=name, timing=timing, **sections)


def profile_table_markdown() -> str:
    """The profile table of docs/noise.md: one row per parameter set by any profile, with value and source per
    profile."""
    names = [n for n in PROFILE_NAMES if n != "none"]
    rows: dict[tuple[str, str], dict[str, tuple[float, str]]] = {}
    for name in names:
        for section, values in profile_sources(name).items():
            for key, entry in values.items():
                rows.setdefault((section, key), {})[name] = entry
    lines = ["| parameter | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for (section, key), by_profile in rows.items():
        cells = [f"{by_profile[n][0]:g} ({by_profile[n][1]})" if n in by_profile else "-" for n in names]
        lines.append(f"| `{section}.{key}` | " + " | ".join(cells) + " |")
    return "\n".join(lines)
