"""Named noise profiles (``profiles.yaml``) and how ``gym.make(..., noise=...)`` resolves them.

``noise`` may be a profile name (``"none"``, ``"nominal"``, ``"low-cost"``, ``"harsh"``), a mapping that starts
from a profile and overrides parameters per section, or a :class:`NoiseProfile`::

    gym.make("ClutterNav-v1", noise={"profile": "nominal", "lidar": {"range_sigma": 0.02, "latency_steps": 1}})

Sections: ``lidar``, ``imu``, ``camera_rgb``, ``camera_depth``, ``camera`` (timing only), ``action`` and
``dynamics``, and each section a sensor's noise module declares (:class:`SensorNoiseSection`: ``odometry``). The
sensor sections ``lidar``, ``imu``, ``camera`` and the declared timed ones also take the timing keys ``rate_hz`` and
``latency_steps`` (:class:`~clutter_gym.noise.timing.SensorTiming`).

A new sensor's noise needs no edit here: its module in this package declares ``SENSOR_NOISE``, a
:class:`SensorNoiseSection` with its parameters, its values in each named profile, each with its source, its model
in words and the source rows it cites, and :func:`sensor_sections` finds it. Its parameters are then
``noise.section(name)``, overridable and listed like the others, and docs/sensors.md (generated) shows its model,
values and sources.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import pkgutil
from collections.abc import Collection, Mapping
from importlib import resources
from typing import Any, NamedTuple

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


class Reference(NamedTuple):
    """A row of a source table, as docs/sensor-noise-reference.md's are: what was looked up, what it says, where."""

    item: str
    value: str
    source: str


@dataclasses.dataclass(frozen=True)
class SensorNoiseSection:
    """A sensor's noise section, declared in its noise module as ``SENSOR_NOISE``.

    Attributes:
        name: the section's name in profiles and overrides (the sensor's name).
        params: its parameters (clean by default).
        timed: it also takes the timing keys (``rate_hz``, ``latency_steps``).
        profiles: ``{profile: {parameter: (value, source)}}`` for the named profiles that set any (timing keys
            included); a source cites a row by its ID (a row of docs/sensor-noise-reference.md or of
            ``references``) or says UNSOURCED and why.
        model: the noise model in words (markdown): what is drawn, when, and in what order.
        references: the rows its sources cite that docs/sensor-noise-reference.md does not hold, by ID.
    """

    name: str
    params: type[NoiseParams]
    timed: bool
    profiles: Mapping[str, Mapping[str, tuple[float, str]]]
    model: str
    references: Mapping[str, Reference] = dataclasses.field(default_factory=dict)


@functools.cache
def sensor_sections() -> dict[str, SensorNoiseSection]:
    """The sections the modules of this package declare (``SENSOR_NOISE``), by name."""
    package = importlib.import_module("clutter_gym.noise")
    found: dict[str, SensorNoiseSection] = {}
    for info in pkgutil.iter_modules(package.__path__):
        declared = getattr(importlib.import_module(f"clutter_gym.noise.{info.name}"), "SENSOR_NOISE", None)
        if isinstance(declared, SensorNoiseSection):
            found[declared.name] = declared
    return found


def _timed() -> tuple[str, ...]:
    """Every section with timing: the built-in sensors' and the declared timed ones."""
    return (*TIMED_SENSORS, *(name for name, section in sensor_sections().items() if section.timed))


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
        default_factory=lambda: {sensor: _timing_class(sensor)() for sensor in _timed()}
    )
    sensors: Mapping[str, NoiseParams] = dataclasses.field(
        default_factory=lambda: {name: section.params() for name, section in sensor_sections().items()}
    )

    def section(self, name: str) -> Any:
        """The noise parameters of section ``name``, a built-in one or a declared sensor's."""
        return getattr(self, name) if name in NOISE_SECTIONS else self.sensors[name]

    def to_dict(self) -> dict[str, Any]:
        """Plain values, in the override format (every parameter, clean ones included)."""
        out: dict[str, Any] = {"profile": self.name}
        for section in (*NOISE_SECTIONS, *self.sensors):
            out[section] = dataclasses.asdict(self.section(section))
        for sensor in self.timing:
            out.setdefault(sensor, {}).update(dataclasses.asdict(self.timing[sensor]))
        return out


@functools.cache
def _profile_file() -> dict[str, dict[str, Any]]:
    text = resources.files("clutter_gym.noise").joinpath("profiles.yaml").read_text(encoding="utf-8")
    return yaml.safe_load(text)


PROFILE_NAMES: tuple[str, ...] = tuple(_profile_file())


def profile_sources(name: str) -> dict[str, dict[str, tuple[float, str]]]:
    """``{section: {parameter: (value, source)}}`` of a named profile as written in profiles.yaml and in the sections
    sensors' noise modules declare (:func:`sensor_sections`)."""
    if name not in PROFILE_NAMES:
        raise ValueError(f"noise profile must be one of {PROFILE_NAMES}, got {name!r}")
    sources = {
        section: {key: (entry[0], entry[1]) for key, entry in values.items()}
        for section, values in _profile_file()[name].items()
        if section != "description"
    }
    for section_name, section in sensor_sections().items():
        if name in section.profiles:
            sources[section_name] = dict(section.profiles[name])
    return sources


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
    allowed = sorted({*NOISE_SECTIONS, *_timed(), *sensor_sections()})
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
    sensors: dict[str, NoiseParams] = {}
    timing: dict[str, SensorTiming] = {}
    declared = sensor_sections()
    timed = _timed()
    for section in sorted({*NOISE_SECTIONS, *timed, *declared}):
        given = dict(values.get(section, {}))
        if section in timed:
            timing[section] = _timing_class(section).from_dict({k: given.pop(k) for k in _TIMING_KEYS if k in given})
        if section in NOISE_SECTIONS:
            sections[section] = NOISE_SECTIONS[section].from_dict(given)
        elif section in declared:
            sensors[section] = declared[section].params.from_dict(given)
        elif given:
            raise ValueError(f"noise section {section!r} takes only {list(_TIMING_KEYS)}, got {sorted(given)}")
    return NoiseProfile(name=name, timing=timing, sensors=sensors, **sections)


def profile_table_markdown(sections: Collection[str] | None = None) -> str:
    """The profile table: one row per parameter set by any profile, with value and source per profile; only the
    rows of ``sections`` when given (docs/noise.md's: those of profiles.yaml, :data:`NOISE_SECTIONS` and
    :data:`TIMED_SENSORS`; docs/sensors.md's: a declared sensor's)."""
    names = [n for n in PROFILE_NAMES if n != "none"]
    rows: dict[tuple[str, str], dict[str, tuple[float, str]]] = {}
    for name in names:
        for section, values in profile_sources(name).items():
            if sections is None or section in sections:
                for key, entry in values.items():
                    rows.setdefault((section, key), {})[name] = entry
    lines = ["| parameter | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for (section, key), by_profile in rows.items():
        cells = [f"{by_profile[n][0]:g} ({by_profile[n][1]})" if n in by_profile else "-" for n in names]
        lines.append(f"| `{section}.{key}` | " + " | ".join(cells) + " |")
    return "\n".join(lines)
