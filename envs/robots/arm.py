"""A position-controlled fixed-base arm: any arm an :class:`~clutter_gym.robots.arm_model.ArmModel` describes (the
Franka Panda of ``robots/panda.py``, the arms of ``robots/registry.py``, a user's from a spec)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.robots.arm_model import ArmModel
from clutter_gym.robots.urdf_robot import UrdfRobot
from clutter_gym.sim import Sim

CONTROLS = ("joint_velocity", "ee_position")
EE_DOWN = (1.0, 0.0, 0.0, 0.0)  # end effector pointing straight down (x, y, z, w)


@dataclass(frozen=True)
class ArmConfig:
    """Control mode and limits.

    Attributes:
        control: "joint_velocity" (one joint-velocity command per arm joint) or "ee_position" (3 end-effector
            displacements).
        max_joint_speed: fraction of each joint's URDF velocity limit commanded by an action of 1, in (0, 1].
        max_ee_step: end-effector displacement per control step commanded by an action of 1, metres.
    """

    control: str = "joint_velocity"
    max_joint_speed: float = 0.5
    max_ee_step: float = 0.05

    def __post_init__(self) -> None:
        if self.control not in CONTROLS:
            raise ValueError(f"control must be one of {CONTROLS}, got {self.control!r}")
        if not (math.isfinite(self.max_joint_speed) and 0.0 < self.max_joint_speed <= 1.0):
            raise ValueError(
                f"max_joint_speed must be in (0, 1] (fraction of the URDF limit), got {self.max_joint_speed!r}"
            )
        if not (math.isfinite(self.max_ee_step) and 0.0 < self.max_ee_step <= 0.2):
            raise ValueError(f"max_ee_step must be in (0, 0.2] metres, got {self.max_ee_step!r}")


class Arm(UrdfRobot):
    """A position-controlled fixed-base arm (``model``): actions become joint targets that pybullet's motors track
    under the arm's effort limits.

    ``joint_velocity``: an (n,) in [-1, 1] commands ``a * max_joint_speed * limit`` rad/s; the joint targets move
    by that times the control period (a joint-position delta per step), clamped to the joint limits and to
    within two steps' travel of the measured position (a blocked arm does not wind up). ``ee_position``: a (3,)
    in [-1, 1] moves the end-effector target by ``a * max_ee_step`` metres; pybullet's IK (hand pointing down)
    turns it into joint targets.
    """

    def __init__(self, model: ArmModel, config: ArmConfig | None = None, control_dt: float = 0.05) -> None:
        self.model = m = model
        self.name, self.base_link = m.name, m.base_link
        self.config = c = config or ArmConfig()
        self.control_dt = control_dt
        self.speed = c.max_joint_speed * m.speed_limit
        n = len(m.arm_joints) if c.control == "joint_velocity" else 3
        self.action_space = spaces.Box(-1.0, 1.0, shape=(n,), dtype=np.float32)
        f32 = np.float32
        self.spaces = {
            "joint_position": spaces.Box(m.lower.astype(f32), m.upper.astype(f32), dtype=f32),
            "joint_velocity": spaces.Box(-2 * m.speed_limit.astype(f32), 2 * m.speed_limit.astype(f32), dtype=f32),
            "ee_position": spaces.Box(-1.5, 1.5, shape=(3,), dtype=f32),
        }
        self._target = np.array(m.ready)
        self._velocity = np.zeros(len(m.arm_joints))
        self._forces = m.effort_limit.copy()
        self._ee_target = np.zeros(3)
        fingers = len(m.finger_joints)
        # pybullet's IK takes every movable joint, in index order: the arm's, then the fingers'
        self._ik_rest = np.concatenate([m.ready, [m.finger_opening] * fingers])
        self._ik_lower = np.concatenate([m.lower, [m.finger_range[0]] * fingers])
        self._ik_upper = np.concatenate([m.upper, [m.finger_range[1]] * fingers])

    @property
    def urdf_path(self) -> Path:
        return self.model.urdf

    def load(self, sim: Sim) -> int:
        """Load the URDF with a fixed base at the origin and look up joint and link indices."""
        self._load(sim, fixed_base=True)
        joints = sim.joint_indices(self._body)
        m = self.model
        self._arm = [joints[name] for name in m.arm_joints]
        self._fingers = [joints[name] for name in m.finger_joints]
        self._index_links(m.tracked_links)
        self._ee = self.link_index[m.ee_link]
        links = sorted(i for i in self.link_index.values() if i >= 0)
        self._nominal = dict(zip(links, sim.actuation.inertial_properties(self._body, links)))
        self._forces = m.effort_limit.copy()
        self._all_movable = sorted(self._arm + self._fingers)
        return self._body

    def _set_motor_scale(self, scale: float) -> None:
        self._forces = self.model.effort_limit * scale

    def reset_to(self, q: tuple[float, ...]) -> None:
        """Arm at joint positions ``q`` (n,) at rest, fingers (if any) at their opening, motors holding."""
        self._sim.actuation.reset_joints(self._body, self._arm, q)
        if self._fingers:
            opening = [self.model.finger_opening] * len(self._fingers)
            self._sim.actuation.reset_joints(self._body, self._fingers, opening)
        self._sim.record.forget_contacts(self._body)
        self._target = np.array(q, dtype=float)
        if self._fingers:
            n = len(self._fingers)
            self._sim.actuation.set_joint_positions(self._body, self._fingers, opening, [0.0] * n, [20.0] * n)
        self._hold(np.zeros(len(self._arm)))
        self._ee_target = self._sim.link_frame(self._body, self._ee)[0]

    def _hold(self, velocity: np.ndarray) -> None:
        self._velocity = velocity
        self._sim.actuation.set_joint_positions(self._body, self._arm, self._target.tolist(), velocity.tolist(),
                                      self._forces.tolist())

    def held_command(self) -> tuple[np.ndarray, np.ndarray]:
        """The arm joints' motor targets the coming ticks hold: positions (rad) and velocities (rad/s)."""
        return self._target, self._velocity

    @property
    def arm_joints(self) -> list[int]:
        """pybullet indices of the arm's joints (each is its child link's index)."""
        return self._arm

    def apply_action(self, action: np.ndarray) -> None:
        """Move the joint targets for one control period from a clipped, normalised action."""
        q, _ = self._sim.actuation.joint_states(self._body, self._arm)
        if self.config.control == "joint_velocity":
            velocity = np.asarray(action, dtype=float) * self.speed
            travel = 2.0 * self.speed * self.control_dt
            target = np.clip(self._target + velocity * self.control_dt, q - travel, q + travel)
        else:
            ee, _ = self._sim.link_frame(self._body, self._ee)
            self._ee_target = ee + np.asarray(action, dtype=float) * self.config.max_ee_step
            solution = self._sim.actuation.inverse_kinematics(self._body, self._ee, self._ee_target, EE_DOWN,
                                                              self._ik_lower, self._ik_upper, self._ik_rest)
            target = solution[[self._all_movable.index(j) for j in self._arm]]
            velocity = (target - q) / self.control_dt
        m = self.model
        self._target = np.clip(target, m.lower, m.upper)
        self._hold(np.clip(velocity, -m.speed_limit, m.speed_limit))

    def state(self) -> RobotState:
        """Ground-truth state from two batched pybullet reads (the base is fixed at the origin)."""
        q, dq = self._sim.actuation.joint_states(self._body, self._arm)
        return RobotState(
            position=np.zeros(3),
            rotation=np.eye(3),
            linear_velocity=(0.0, 0.0, 0.0),
            angular_velocity=(0.0, 0.0, 0.0),
            links=self._sim.link_states(self._body, self._tracked),
            link_names=self.link_names,
            link_index=self.link_index,
            body=self._body,
            joint_position=q,
            joint_velocity=dq,
        )

    def ee_position(self, state: RobotState) -> np.ndarray:
        """End-effector (between the fingertips) position, world frame, metres."""
        return state.links.position[self.model.ee_row]

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """The end effector (world frame, metres) and a radius that takes in the hand's fingers: what the
        ``rgb_array`` view rings and trails, as the point that must reach the target."""
        return self.ee_position(state), self.model.hand_radius

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """Joint positions (rad), joint velocities (rad/s, clipped to twice the limits), end-effector position (m)."""
        space = self.spaces["joint_velocity"]
        return {
            "joint_position": np.clip(state.joint_position, self.model.lower, self.model.upper).astype(np.float32),
            "joint_velocity": np.clip(state.joint_velocity, space.low, space.high).astype(np.float32),
            "ee_position": self.ee_position(state).astype(np.float32),
        }
