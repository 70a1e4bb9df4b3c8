"""The settings of an env, flat or nested, resolved into one checked set before any part is built.

Every setting has a flat name, its ``gym.make`` keyword argument (``n_rays=64``, ``progress_weight=5.0``), and a
place in the nested form, which groups the settings of one part by the names of that part's own settings object
(``sensors={"lidar": {"n_rays": 64}, "imu": {}}``, ``reward={"progress": 5.0}``). :data:`ALIASES` is the one table
from flat names to nested places; a ``<term>_weight`` is the reward's ``term``, and a name in neither stays at the
top under its own name (``robot``, ``noise``, ``control_hz``). The nested ``sensors`` is also the sensors' list: its
keys are the sensors the env carries, in order, each with its settings (``{}`` for its defaults). A registered sensor
the env declares no settings for takes its own, the fields of its registered default config
(:meth:`~clutter_gym.sensors.suite.SensorEntry.settings`), nested only: a new sensor's settings need no edit here or in
an env module.

An env module declares its settings once, as an :class:`EnvSettings` (each flat name with its default, in the order
of the env's page), gives its constructor their signature (:meth:`EnvSettings.sign`) and starts it with
:meth:`EnvSettings.resolve`: the given settings, flat and nested, become one :class:`Settings` (every flat name with
its value), with the checks every env shares made. A setting given both ways, or a nested key the env does not have,
is refused naming it; a value error names the flat argument, whichever way the value came. To add a setting:
docs/architecture.md, "Settings".
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, TypeVar

from clutter_gym.dynamics import check_dynamics_mode
from clutter_gym.make_checks import (
    check_env_settings,
    check_flags,
    check_numbers,
    check_physics_mode,
    check_swept_speed,
    did_you_mean,
)
from clutter_gym.sensors import SENSORS, CameraConfig, ImuConfig, LidarConfig, camera_config, check_sensor_names
from clutter_gym.util.checks import is_number, short_repr

#: flat name -> its place in the nested form, by the fields of the part's settings object: the sensors' configs
#: (:class:`LidarConfig`, :func:`camera_config`'s arguments), the world's spec (``ClutterSpec``, ``TableSpec``,
#: ``VolumeSpec``), the collision monitor's :class:`SafetyConfig` and :func:`collision_checker`'s arguments.
ALIASES: dict[str, tuple[str, ...]] = {
    "n_rays": ("sensors", "lidar", "n_rays"), "lidar_fov": ("sensors", "lidar", "fov"),
    "lidar_range": ("sensors", "lidar", "max_range"), "lidar_mount_height": ("sensors", "lidar", "mount_height"),
    "lidar_channels": ("sensors", "lidar", "n_channels"), "lidar_vertical_fov": ("sensors", "lidar", "vertical_fov"),
    "lidar_caster": ("sensors", "lidar", "caster"),
    "camera_size": ("sensors", "camera", "size"), "camera_modes": ("sensors", "camera", "modes"),
    "camera_fov": ("sensors", "camera", "fov"), "camera_far": ("sensors", "camera", "far"),
    "camera_renderer": ("sensors", "camera", "renderer"),
    "arena_size": ("world", "arena_size"), "volume_size": ("world", "size"),
    "obstacle_density": ("world", "obstacle_density"), "n_obstacles": ("world", "n_obstacles"),
    "movable_obstacles": ("world", "movable_fraction"), "shelf": ("world", "shelf"), "ceiling": ("world", "ceiling"),
    "safety_horizon": ("safety", "horizon"), "safety_margin": ("safety", "margin"),
    "safety_recovery": ("safety", "recovery"),
    "collision_fidelity": ("collision", "fidelity"), "collision_padding": ("collision", "padding"),
    "contact_tolerance": ("collision", "contact_tolerance"), "swept_speed": ("collision", "swept_speed"),
    "self_collision": ("collision", "self_collision"),
}
#: flat name -> the check of its value, for the settings more than one env has whose part does not check them
SETTING_CHECKS: dict[str, Callable[[Any], None]] = {
    "physics": check_physics_mode, "dynamics": check_dynamics_mode, "swept_speed": check_swept_speed,
}

Init = TypeVar("Init", bound=Callable[..., None])


def nested_path(name: str) -> tuple[str, ...]:
    """The place of the flat setting ``name`` in the nested form (see :data:`ALIASES`); a sensor's own setting, which
    has no flat name, is kept under its nested one (``"sensors.odometry.<field>"``)."""
    if "." in name:
        return tuple(name.split("."))
    if name in ALIASES:
        return ALIASES[name]
    if name.endswith("_weight"):
        return ("reward", name.removesuffix("_weight"))
    return (name,)


class Settings:
    """An env's settings, resolved: each flat setting as an attribute (``s.n_rays``), and each nested group of them
    by :meth:`group`."""

    def __init__(self, values: Mapping[str, Any]) -> None:
        self.values = dict(values)

    def __getattr__(self, name: str) -> Any:
        try:
            return self.__dict__["values"][name]
        except KeyError:
            raise AttributeError(f"no setting {name!r}") from None

    def group(self, *path: str) -> dict[str, Any]:
        """The settings directly under ``path`` in the nested form, by their nested names: ``group("reward")`` are
        the reward weights by term, ``group("sensors", "lidar")`` the LIDAR config's fields."""
        places = {name: nested_path(name) for name in self.values}
        return {place[-1]: self.values[name] for name, place in places.items()
                if len(place) == len(path) + 1 and place[:-1] == path}


@dataclass(frozen=True)
class EnvSettings:
    """The settings an env takes: ``defaults`` has each flat name with its default, in the order of the env's page.

    ``env_id`` and ``min_physics_hz`` (the env's floor on the physics rate) go into the shared checks' messages.
    """

    env_id: str
    min_physics_hz: float
    defaults: Mapping[str, Any]
    places: dict[tuple[str, ...], str] = field(init=False)  # nested path -> flat name
    groups: tuple[str, ...] = field(init=False)  # the top-level names that take a mapping of settings

    def __post_init__(self) -> None:
        places = {nested_path(name): name for name in self.defaults}
        if len(places) != len(self.defaults):
            raise ValueError(f"{self.env_id}: two settings share one nested place")
        object.__setattr__(self, "places", places)
        object.__setattr__(self, "groups", tuple(dict.fromkeys(path[0] for path in places if len(path) > 1)))

    def sign(self, init: Init) -> Init:
        """``init`` (the env's ``__init__(self, **settings)``) with the signature of these settings: each flat one
        with its default, then each group that is not also a flat setting, defaulting to None (nothing nested).
        ``gym.make``'s keyword check, ``help()`` and the env's page read it."""
        keyword = inspect.Parameter.KEYWORD_ONLY
        init.__signature__ = inspect.Signature([  # type: ignore[attr-defined]
            inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD),
            *(inspect.Parameter(name, keyword, default=default) for name, default in self.defaults.items()),
            *(inspect.Parameter(group, keyword, default=None) for group in self.groups if group not in self.defaults)])
        return init

    def resolve(self, given: Mapping[str, Any]) -> Settings:
        """The settings ``given`` to the constructor, flat and nested, over the defaults, with the shared checks made:
        numbers, the rates, the switches (made plain bools) and :data:`SETTING_CHECKS`.

        Raises:
            TypeError: an unknown setting, flat or nested, or one given both flat and nested.
            ValueError: a value out of its range, naming the flat setting; a group that is not a mapping.
        """
        nested = self._unnest(given)
        values = dict(self.defaults)
        for name, value in given.items():
            if name in self.groups and (isinstance(value, Mapping) or name not in self.defaults):
                continue  # a group: its settings are in nested
            if name not in self.defaults:
                raise TypeError(f"{self.env_id} has no setting {name!r}{did_you_mean(name, list(self.defaults))}")
            if name in nested:
                raise TypeError(f"{name} and {nested[name][1]} are one setting; give it once, flat or nested")
            values[name] = value
        values.update({name: value for name, (value, _) in nested.items()})
        self._check(values)
        return Settings(values)

    def _unnest(self, given: Mapping[str, Any]) -> dict[str, tuple[Any, str]]:
        """flat name -> (value, its nested name) of each setting the groups in ``given`` hold."""
        found: dict[str, tuple[Any, str]] = {}
        for group in self.groups:
            node = given.get(group)
            if node is None or (group in self.defaults and not isinstance(node, Mapping)):
                continue  # not given, or given flat (the sensors' names)
            if group == "sensors":  # its keys: the sensors the env carries, in order
                found["sensors"] = (check_sensor_names(tuple(node)), "sensors")
            self._walk((group,), node, found)
        return found

    def _walk(self, path: tuple[str, ...], node: Any, found: dict[str, tuple[Any, str]]) -> None:
        where = ".".join(path)
        if not isinstance(node, Mapping):
            raise ValueError(f"{where} must be a mapping of settings by name, got {short_repr(node)}")
        below = list(dict.fromkeys(p[len(path)] for p in self.places if len(p) > len(path) and p[:len(path)] == path))
        # a sensor this env declares no settings for takes its own
        own = SENSORS[path[1]].settings() if not below and len(path) == 2 and path[0] == "sensors" else {}
        below = below or list(own)
        for key, value in node.items():
            place = (*path, key)
            if place in self.places:
                found[self.places[place]] = (value, ".".join(map(str, place)))
            elif key in own:  # a sensor's own setting: no flat name, kept under its nested one
                found[f"{where}.{key}"] = (value, f"{where}.{key}")
            elif key in below or path == ("sensors",):  # a sub-group, or a sensor
                self._walk(place, value, found)
            else:  # a flat name given nested is pointed to its nested one
                flat = {self.places[p]: p[-1] for p in self.places if p[:-1] == path}
                hint = f" (did you mean {flat[key]!r}?)" if key in flat else did_you_mean(key, below)
                raise TypeError(f"unknown setting {where}.{key}{hint}; {where} takes "
                                f"{sorted(below) if below else 'no settings'}")

    def _check(self, values: dict[str, Any]) -> None:
        """The checks every env shares, in place: switches become plain bools."""
        check_numbers(**{name: values[name] for name, default in self.defaults.items() if is_number(default)})
        check_env_settings(values["render_mode"], values["physics_hz"], values["control_hz"],
                           values["solver_iterations"], values["contact_tolerance"], env_id=self.env_id,
                           min_physics_hz=self.min_physics_hz)
        for name, check in SETTING_CHECKS.items():
            if name in values:
                check(values[name])
        flags = {name: values[name] for name, default in self.defaults.items() if isinstance(default, bool)}
        check_flags(**flags)
        values.update({name: bool(value) for name, value in flags.items()})


def sensor_configs(s: Settings, sensor_link: str | None = None, imu_link: str | None = None) -> dict[str, Any]:
    """The sensors' configs by name of an env's settings: the LIDAR, IMU and camera configs (ClutterNav's and
    ClutterFly's: every LIDAR and camera setting), and each other carried sensor's registered default config with the
    settings given for it; ``sensor_link`` mounts the LIDAR and the camera, ``imu_link`` the IMU, where the robot's
    links differ from the configs' defaults.

    Raises:
        ValueError: a value out of its config's range, naming the setting.
    """
    lidar = LidarConfig(**s.group("sensors", "lidar"))
    camera: CameraConfig = camera_config(**s.group("sensors", "camera"))
    imu = ImuConfig(dt=1.0 / s.control_hz)
    if sensor_link is not None:
        lidar, camera = replace(lidar, link=sensor_link), replace(camera, link=sensor_link)
    if imu_link is not None:
        imu = replace(imu, link=imu_link)
    configs = {"lidar": lidar, "imu": imu, "camera": camera}
    for name in s.sensors:
        given = s.group("sensors", name)
        if name not in configs and given:
            configs[name] = SENSORS[name].configured(given)
    return configs
