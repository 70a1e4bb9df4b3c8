"""A velocity-commanded wheeled base: the differential drive of assets/robots/diffbot.urdf (two driven wheels, two
frictionless casters) by default, or any base a :class:`~clutter_gym.robots.wheeled.WheeledBase` describes."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.robots.state import floating_base_state
from clutter_gym.robots.urdf_robot import UrdfRobot
from clutter_gym.robots.wheeled import WheeledBase, diffbot
from clutter_gym.sim import Sim
from clutter_gym.util.transforms import quat_to_matrix, yaw_quat

#: The diffbot's links whose states are read every step: the IMU, the LIDAR (the exact ray caster casts from its frame)
#: and every link with collision geometry.
TRACKED_LINKS = diffbot().tracked_links


@dataclass(frozen=True)
class DiffDriveConfig:
    """Drive limits and wheel geometry.

    Attributes:
        max_linear_speed: forward speed commanded by action[0] = 1, m/s.
        max_angular_speed: yaw rate commanded by action[1] = 1, rad/s (counter-clockwise positive).
        max_wheel_torque: motor torque limit per wheel, N m.
        wheel_radius: metres; must match the URDF.
        wheel_separation: distance between the wheel contact centres, metres; must match the URDF.
        footprint_radius: radius of the circle that encloses the robot seen from above, metres.

    The last four are the diffbot's; a robot on another base takes them from its :class:`WheeledBase`.
    """

    max_linear_speed: float = 0.5
    max_angular_speed: float = 2.0
    max_wheel_torque: float = 1.5
    wheel_radius: float = 0.05
    wheel_separation: float = 0.29
    footprint_radius: float = 0.17

    def __post_init__(self) -> None:
        for field, hi in (("max_linear_speed", 2.0), ("max_angular_speed", 10.0), ("max_wheel_torque", 500.0)):
            value = getattr(self, field)
            if not (np.isfinite(value) and 0.0 < value <= hi):
                raise ValueError(f"{field} must be in (0, {hi}], got {value!r}")


class DiffDriveRobot(UrdfRobot):
    """Velocity-commanded differential drive.

    Action: Box(-1, 1, (2,)) = (linear, angular) velocity command normalised by the configured maxima. Values
    outside [-1, 1] are clipped by the env before they reach :meth:`apply_action`. The command becomes wheel
    speeds through the unicycle model ``w_l = (v - w L/2) / r``, ``w_r = (v + w L/2) / r`` and is tracked by
    pybullet's velocity motors under the torque limit, so the robot accelerates and slips realistically. A zero
    command holds the wheels at their angles with the same torque limit, as a real base's wheel-speed loop does
    at standstill, and anchors their contacts: pybullet's velocity motors and re-anchored friction alone let a
    still robot creep (docs/design-notes.md#standing-still).
    """

    def __init__(self, config: DiffDriveConfig | None = None, base: WheeledBase | None = None) -> None:
        self.base = base or diffbot()
        b = self.base
        self.name, self.base_link = b.name, b.base_link
        self.config = replace(config or DiffDriveConfig(), wheel_radius=b.wheel_radius,
                              wheel_separation=b.wheel_separation, footprint_radius=b.footprint_radius,
                              max_wheel_torque=b.max_wheel_torque)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        c = self.config
        self.velocity_bound = np.array([2.0 * c.max_linear_speed, 2.0 * c.max_angular_speed], dtype=np.float32)
        self.spaces = {"velocity": spaces.Box(-self.velocity_bound, self.velocity_bound, dtype=np.float32)}
        self._velocity_limits = (float(self.velocity_bound[0]), float(self.velocity_bound[1]))
        self._hold: list[float] | None = None  # wheel angles held while the command is zero

    @property
    def urdf_path(self) -> Path:
        return self.base.urdf

    @property
    def wheel_joints(self) -> list[int]:
        """pybullet joint indices of the wheels, the left ones first."""
        return list(self._wheels)

    @property
    def tracked_links(self) -> list[int]:
        """pybullet link indices read every step, in the order of the base's ``tracked_links``."""
        return list(self._tracked)

    def load(self, sim: Sim) -> int:
        """Load the URDF into ``sim`` and look up joint and link indices."""
        self._load(sim)
        self._hold = None
        joints = sim.joint_indices(self._body)
        b = self.base
        self._wheels = [joints[name] for name in (*b.left_wheels, *b.right_wheels)]
        self._n_left = len(b.left_wheels)
        self._index_links(b.tracked_links)
        self._com_offset = sim.base_inertial_offset(self._body)
        self._torques = [self.config.max_wheel_torque] * len(self._wheels)
        self._still = [0.0] * len(self._wheels)
        links = [-1, *sorted(self.link_index.values())]
        self._nominal = dict(zip(links, sim.actuation.inertial_properties(self._body, links)))
        return self._body

    @property
    def com_offset(self) -> np.ndarray:
        """The base's centre of mass in the base link frame, metres (where pybullet puts the base's pose)."""
        return self._com_offset

    def _set_motor_scale(self, scale: float) -> None:
        self._torques = [self.config.max_wheel_torque * scale] * len(self._wheels)

    def reset_to(self, start: tuple[float, ...]) -> None:
        """Place the robot at rest at ``start`` = (x m, y m, yaw rad)."""
        self.reset_pose(*start)

    def reset_pose(self, x: float, y: float, yaw: float) -> None:
        """Place the robot at rest on the floor at (x, y) with heading ``yaw`` (rad), wheels stopped."""
        q = yaw_quat(yaw)
        com = np.array([x, y, self.base.base_height]) + quat_to_matrix(np.array(q)) @ self._com_offset
        self._sim.set_pose(self._body, com, q)
        self._sim.record.forget_contacts(self._body)  # the same seed must not warm-start from the last episode
        self._sim.actuation.reset_joints(self._body, self._wheels)
        self.release_hold()
        self._sim.actuation.set_joint_velocities(self._body, self._wheels, self._still, self._torques)

    def release_hold(self) -> None:
        """End a standstill hold (if any): the wheels go back to velocity control with re-anchored friction."""
        if self._hold is not None:
            self._hold = None
            self._sim.actuation.set_friction_anchors(self._body, self._wheels, False)

    def apply_action(self, action: np.ndarray) -> None:
        """Command wheel speeds from a clipped, normalised (linear, angular) action."""
        c = self.config
        v = float(action[0]) * c.max_linear_speed
        w = float(action[1]) * c.max_angular_speed
        if v == 0.0 and w == 0.0:
            if self._hold is None:
                self._hold = self._sim.actuation.joint_states(self._body, self._wheels)[0].tolist()
                self._sim.actuation.set_friction_anchors(self._body, self._wheels, True)
            self._sim.actuation.set_joint_positions(self._body, self._wheels, self._hold, self._still, self._torques)
            return
        self.release_hold()
        half = 0.5 * c.wheel_separation
        left = (v - w * half) / c.wheel_radius
        right = (v + w * half) / c.wheel_radius
        n = self._n_left
        self._sim.actuation.set_joint_velocities(self._body, self._wheels,
                                                 [left] * n + [right] * (len(self._wheels) - n), self._torques)

    def state(self) -> RobotState:
        """Ground-truth state from batched pybullet reads."""
        return floating_base_state(self._sim, self._body, self._com_offset, self._tracked, self.link_names,
                                   self.link_index)

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """The chassis centre (world frame, metres) and its footprint radius: what the ``rgb_array`` view rings."""
        return state.position + state.rotation[:, 2] * self.base.focus_height, self.config.footprint_radius

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """``velocity``: (forward speed m/s, yaw rate rad/s) in the base frame, clipped to twice the commanded
        maxima."""
        r, lin, ang = state.rotation, state.linear_velocity, state.angular_velocity
        v = r[0, 0] * lin[0] + r[1, 0] * lin[1] + r[2, 0] * lin[2]
        w = r[0, 2] * ang[0] + r[1, 2] * ang[1] + r[2, 2] * ang[2]
        v_max, w_max = self._velocity_limits
        return {"velocity": np.array([min(max(v, -v_max), v_max), min(max(w, -w_max), w_max)], dtype=np.float32)}
