"""The sensors by name: a registry of what each sensor is built from, and an env's set built from its
``sensors=(...)`` names, each sensor's config (by name) and the noise profile.

A sensor registers once (:func:`register_sensor`, in ``sensors/__init__.py``) with the function that builds it
from its config, the profile and the robot it is mounted on, the config it takes when an env gives none, and the
URDF link it is mounted on, and the observation entries it adds (:class:`Observed`, the rows of its section in
docs/sensors.md, which is generated from this registry). Callers pass configs by sensor name, so a new sensor changes
no caller. The fields of its default config are its settings (:meth:`SensorEntry.settings`): an env takes them
nested, ``sensors={"<name>": {<field>: value}}``, with no edit of the builder or the env. A sensor's noise section
lives in its noise module (:mod:`clutter_gym.noise.profiles` finds it there).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

from clutter_gym.interfaces import Sensor
from clutter_gym.noise.profiles import NoiseProfile


class Observed(NamedTuple):
    """One observation entry a sensor adds, as a row of docs/sensors.md (markdown; settings by their nested names)."""

    key: str
    shape: str
    content: str
    units: str  # units and frame
    bounds: str


@dataclass(frozen=True)
class SensorEntry:
    """One registered sensor.

    Attributes:
        name: its name in ``sensors=(...)`` and in the noise profile's timing.
        build: the sensor from its config, the env's noise profile (which holds its noise section) and the robot
            (a sensor that reads the robot's own parts, such as its wheels, takes them from it).
        default_config: the config used when an env passes none for it; None: an env must pass one (the IMU's
            depends on the env's control period).
        link: the URDF link it is mounted on (an env checks the robot has it); None: it is not mounted on a link.
        observation: the observation entries it adds.
    """

    name: str
    build: Callable[[Any, NoiseProfile, Any], Sensor]
    default_config: Callable[[], Any] | None
    link: str | None
    observation: tuple[Observed, ...] = ()

    def settings(self) -> dict[str, Any]:
        """The settings an env takes for this sensor nested (``sensors={name: {...}}``) where it declares none of its
        own: each field of the default config (a dataclass) with its default, but the mount (``link``), which is the
        robot's; none for a sensor whose default config is not a dataclass."""
        config = self.default_config() if self.default_config is not None else None
        if isinstance(config, type) or not dataclasses.is_dataclass(config):
            return {}
        return {f.name: getattr(config, f.name) for f in dataclasses.fields(config) if f.init and f.name != "link"}

    def configured(self, settings: Mapping[str, Any]) -> Any:
        """The default config with ``settings`` (some of :meth:`settings`) in place of their defaults; the config's
        own checks run."""
        assert self.default_config is not None, f"sensor {self.name!r} takes no settings"
        return dataclasses.replace(self.default_config(), **settings)


#: The registered sensors, by name, in registration order.
SENSORS: dict[str, SensorEntry] = {}


def register_sensor(name: str, build: Callable[[Any, NoiseProfile, Any], Sensor],
                    default_config: Callable[[], Any] | None, link: str | None = "",
                    observation: Sequence[Observed] = ()) -> None:
    """Make ``name`` a sensor an env can be given, mounted on ``link`` ("": the link called ``<name>_link``), adding
    the ``observation`` entries.

    Raises:
        ValueError: the name is taken.
    """
    if name in SENSORS:
        raise ValueError(f"sensor {name!r} is already registered")
    SENSORS[name] = SensorEntry(name, build, default_config, f"{name}_link" if link == "" else link, tuple(observation))


def check_sensor_names(sensors: Sequence[str]) -> tuple[str, ...]:
    """The ``sensors`` kwarg as a tuple, or a ValueError naming the allowed sensors."""
    allowed = tuple(SENSORS)
    if isinstance(sensors, str) or not isinstance(sensors, Sequence):
        raise ValueError(f"sensors must be a tuple of names from {allowed}, got {sensors!r}")
    unknown = [s for s in sensors if s not in SENSORS]
    if unknown:
        raise ValueError(f"unknown sensors {unknown}; allowed: {allowed}")
    if len(set(sensors)) != len(sensors):
        raise ValueError(f"sensors must not repeat a name, got {tuple(sensors)}")
    return tuple(sensors)


def build_sensors(names: Sequence[str], noise: NoiseProfile, configs: Mapping[str, Any], robot: Any) -> list[Sensor]:
    """One sensor per name, in order, on ``robot``, from its config in ``configs`` (its registered default when
    absent), each with its noise from the profile.

    Raises:
        ValueError: an unknown or repeated name, a config for a sensor that is not registered, or none for a named
            sensor that has no default.
    """
    unknown = sorted(set(configs) - set(SENSORS))
    if unknown:
        raise ValueError(f"configs for unknown sensors {unknown}; registered: {tuple(SENSORS)}")
    sensors = []
    for entry in (SENSORS[name] for name in check_sensor_names(names)):
        if entry.name in configs:
            config = configs[entry.name]
        elif entry.default_config is not None:
            config = entry.default_config()
        else:
            raise ValueError(f"sensor {entry.name!r} has no default config: pass one under configs[{entry.name!r}]")
        sensors.append(entry.build(config, noise, robot))
    return sensors


def sensor_links(names: Sequence[str]) -> list[str]:
    """The URDF links the sensors ``names`` are mounted on (those mounted on one)."""
    return [link for link in (SENSORS[name].link for name in check_sensor_names(names)) if link is not None]
