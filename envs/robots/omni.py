"""An omnidirectional (holonomic) base: it moves in any direction of the floor and turns at the same time.

Its wheel units (mecanum or omni wheels) are not simulated roller by roller: the chassis rests on frictionless
ball casters, and before every physics tick the base's controller pushes it with a planar force through its centre
of mass (so pushing does not turn it, as a holonomic base's controller shares the push among its wheels) and a yaw
torque,
``F = m (v_cmd - v) / response_time`` and ``tau = I_zz (w_cmd - w) / response_time``, each within what the wheel
units can give (``max_acceleration`` times the nominal mass, ``max_angular_acceleration`` times the nominal yaw
inertia; an episode's motor strength scales both). So it tracks a body-frame velocity command ``(v_x, v_y, w)``
as a first-order lag under acceleration limits, and contacts push it back as they push any rigid body.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from gymnasium import spaces

from clutter_gym.assets import asset_path
from clutter_gym.datatypes import RobotState
from clutter_gym.robots.spec_reading import check_keys, load_spec_urdf, number, spec_mounts
from clutter_gym.robots.state import floating_base_state
from clutter_gym.robots.urdf_robot import UrdfRobot
from clutter_gym.robots.wheeled import SENSOR_LINKS, footprint_radius
from clutter_gym.sim import Sim
from clutter_gym.util.transforms import quat_to_matrix, yaw_quat

#: The keys of an ``omni`` spec (besides ``kind``); the first is required.
SPEC_KEYS = ("urdf", "name", "footprint_radius", "base_height", "max_acceleration", "max_angular_acceleration",
             "mounts")


@dataclass(frozen=True)
class OmniModel:
    """An omnidirectional base's URDF and the facts about it the env uses.

    Attributes:
        name, urdf, base_link: as a wheeled base's (:class:`~clutter_gym.robots.wheeled.WheeledBase`).
        footprint_radius: the radius about the base origin that encloses the robot from above, metres.
        base_height: height of the base frame above the floor at rest, metres.
        tracked_links: links read every step: every link with collision geometry, and the sensor links.
        max_acceleration: m/s^2 the wheel units give the base; max_angular_acceleration: rad/s^2.
    """

    name: str
    urdf: Path
    base_link: str
    footprint_radius: float
    base_height: float
    tracked_links: tuple[str, ...]
    max_acceleration: float = 2.0
    max_angular_acceleration: float = 8.0


def omnibot() -> OmniModel:
    """The shipped omnidirectional base (``assets/robots/omnibot.urdf``)."""
    return OmniModel(name="omnibot", urdf=asset_path("robots/omnibot.urdf"), base_link="base_link",
                     footprint_radius=0.19, base_height=0.05,
                     tracked_links=("front_left_caster", "front_right_caster", "rear_left_caster",
                                    "rear_right_caster", "imu_link", "lidar_link"))


def omni_from_spec(spec: Mapping[str, object], where: str, folder: Path | None = None) -> OmniModel:
    """The base an ``omni`` spec describes (keys :data:`SPEC_KEYS`); ``urdf`` relative to ``folder``.

    Raises:
        ValueError: a key is missing, unknown or out of range, or the URDF lacks the LIDAR and IMU links.
    """
    check_keys(spec, SPEC_KEYS, 1, "omni", where)
    urdf = load_spec_urdf(spec, where, folder, spec_mounts(spec, where))
    kinematics, elements = urdf.kinematics, urdf.elements
    links = set(kinematics.links)
    if "lidar_link" not in links or "imu_link" not in links:
        raise ValueError(f"{where}: {urdf.source} has no lidar_link and imu_link; add them with mounts (its links: "
                         f"{kinematics.links})")
    frames = kinematics.forward(np.zeros((1, len(kinematics.joints))))
    lowest = min((frames[e.link][0] @ _origin(e.position))[2] - _half_height(e.kind, e.size) for e in elements)
    geometric = sorted({e.link for e in elements} - {kinematics.root}, key=kinematics.links.index)
    return OmniModel(
        name=urdf.name, urdf=urdf.urdf, base_link=kinematics.root,
        footprint_radius=number(spec, "footprint_radius", where, footprint_radius(elements, frames), 0.01, 5.0,
                                derived=f"the collision shapes of {urdf.source} seen from above"),
        base_height=number(spec, "base_height", where, -lowest, 0.0, 2.0,
                           derived=f"the lowest collision shape of {urdf.source}"),
        tracked_links=(*geometric, *(link for link in SENSOR_LINKS if link in links and link not in geometric)),
        max_acceleration=number(spec, "max_acceleration", where, 2.0, 0.01, 100.0),
        max_angular_acceleration=number(spec, "max_angular_acceleration", where, 8.0, 0.01, 1000.0),
    )


def _origin(position: np.ndarray) -> np.ndarray:
    return np.append(np.asarray(position, dtype=float), 1.0)


def _half_height(kind: str, size: tuple[float, ...]) -> float:
    """How far a collision element reaches below its origin (upright elements; a mesh by its bounding box)."""
    return size[0] if kind == "sphere" else 0.5 * size[-1] if kind in ("box", "mesh") else 0.5 * size[1] + (
        size[0] if kind == "capsule" else 0.0)


@dataclass(frozen=True)
class OmniConfig:
    """Drive limits: ``max_linear_speed`` m/s in any direction of the floor, ``max_angular_speed`` rad/s, and
    ``response_time`` s, the time constant of the velocity tracking."""

    max_linear_speed: float = 0.5
    max_angular_speed: float = 2.0
    response_time: float = 0.1


class OmniBase(UrdfRobot):
    """A velocity-commanded holonomic base (see the module docstring).

    Action: Box(-1, 1, (3,)) = (forward, leftward, yaw rate) command in the base frame, normalised by the
    configured maxima (the planar speed is then capped at ``max_linear_speed``). A :class:`TickedRobot`: its
    controller acts before every physics tick.
    """

    ticked = True

    def __init__(self, config: OmniConfig | None = None, model: OmniModel | None = None) -> None:
        self.base = model or omnibot()
        self.name, self.base_link = self.base.name, self.base.base_link
        self.config = c = config or OmniConfig()
        self.footprint_radius = self.base.footprint_radius
        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        bound = np.array([2.0 * c.max_linear_speed] * 2 + [2.0 * c.max_angular_speed], dtype=np.float32)
        self.spaces = {"velocity": spaces.Box(-bound, bound, dtype=np.float32)}
        self._bound = bound
        self._command = (0.0, 0.0, 0.0)
        self._strength = 1.0

    @property
    def urdf_path(self) -> Path:
        return self.base.urdf

    def load(self, sim: Sim) -> int:
        self._load(sim)
        self._world = sim  # the Sim, typed as loaded
        sim.actuation.set_damping(self._body, 0.0, 0.0)  # pybullet's default damping would drag on the velocity loop
        self._index_links(self.base.tracked_links)
        self._com_offset = sim.base_inertial_offset(self._body)
        com, rotation, _, _ = sim.base_state(self._body)
        # where the whole body's centre of mass sits from the base link's, in the base frame
        self._whole_com = np.reshape(rotation, (3, 3)).T @ (sim.actuation.centre_of_mass(self._body) - np.asarray(com))
        links = [-1, *sorted(self.link_index.values())]
        self._nominal = dict(zip(links, sim.actuation.inertial_properties(self._body, links)))
        self._mass = sum(mass for mass, _, _ in self._nominal.values())
        # the links' own yaw inertias (the casters' offsets add under 10% on the omnibot, left out)
        self._yaw_inertia = sum(inertia[2] for _, _, inertia in self._nominal.values())
        return self._body

    def _set_motor_scale(self, scale: float) -> None:
        self._strength = scale

    def reset_to(self, start: tuple[float, ...]) -> None:
        """Place the base at rest at ``start`` = (x m, y m, yaw rad) on the floor, its command zero."""
        x, y, yaw = start
        q = yaw_quat(yaw)
        self._world.set_pose(self._body, np.array([x, y, self.base.base_height]) + quat_to_matrix(np.array(q))
                           @ self._com_offset, q)
        self._world.record.forget_contacts(self._body)
        self._command = (0.0, 0.0, 0.0)

    def apply_action(self, action: np.ndarray) -> None:
        """Set the body-frame velocity command of a clipped, normalised action."""
        c = self.config
        vx, vy = float(action[0]) * c.max_linear_speed, float(action[1]) * c.max_linear_speed
        speed = math.hypot(vx, vy)
        if speed > c.max_linear_speed:
            vx, vy = vx * c.max_linear_speed / speed, vy * c.max_linear_speed / speed
        self._command = (vx, vy, float(action[2]) * c.max_angular_speed)

    def before_tick(self) -> None:
        """Push the chassis towards the commanded velocity for the next physics tick."""
        _, rot, lin, ang = self._world.base_state(self._body)
        vx, vy, w = self._command
        cos, sin = rot[0], rot[3]  # the base's x axis in the world, from the rotation matrix's first column
        tau = self.config.response_time
        force_limit = self.base.max_acceleration * self._mass * self._strength
        fx = self._mass * (cos * vx - sin * vy - lin[0]) / tau
        fy = self._mass * (sin * vx + cos * vy - lin[1]) / tau
        norm = math.hypot(fx, fy)
        if norm > force_limit:
            fx, fy = fx * force_limit / norm, fy * force_limit / norm
        torque_limit = self.base.max_angular_acceleration * self._yaw_inertia * self._strength
        torque = min(max(self._yaw_inertia * (w - ang[2]) / tau, -torque_limit), torque_limit)
        # the force acts at the base link's centre of mass: add the moment that moves it to the whole body's
        ox, oy, oz = self._whole_com
        rx, ry, rz = (rot[0] * ox + rot[1] * oy + rot[2] * oz, rot[3] * ox + rot[4] * oy + rot[5] * oz,
                      rot[6] * ox + rot[7] * oy + rot[8] * oz)
        self._world.actuation.apply_base_wrench(self._body, (fx, fy, 0.0),
                                                (-rz * fy, rz * fx, torque + rx * fy - ry * fx))

    def state(self) -> RobotState:
        return floating_base_state(self._world, self._body, self._com_offset, list(self._tracked), self.link_names,
                                   self.link_index)

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        return state.position + state.rotation[:, 2] * 0.025, self.base.footprint_radius

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """``velocity``: (forward, leftward speed m/s, yaw rate rad/s) in the base frame, clipped to twice the
        commanded maxima."""
        r, lin, ang = state.rotation, np.asarray(state.linear_velocity), np.asarray(state.angular_velocity)
        body = np.array([r[:, 0] @ lin, r[:, 1] @ lin, r[:, 2] @ ang])
        return {"velocity": np.clip(body, -self._bound, self._bound).astype(np.float32)}
