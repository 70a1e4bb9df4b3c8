"""Franka Emika Panda arm (pybullet_data ``franka_panda/panda.urdf``), fixed base, fingers held half open."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from gymnasium import spaces

from clutter_gym.noise.dynamics import DynamicsSample
from clutter_gym.robots.dynamics import scale_link_dynamics
from clutter_gym.robots.state import RobotState
from clutter_gym.sim import Sim, pybullet_data_file

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
FINGER_OPENING = 0.02  # metres per finger: half open, the fingers never move
EE_LINK = "panda_grasptarget"  # between the fingertips, 0.105 m along the hand's z axis
#: Links read every step: every link with collision geometry, and the end effector.
TRACKED_LINKS = (*(f"panda_link{i}" for i in range(1, 8)), "panda_hand", "panda_leftfinger", "panda_rightfinger",
                 EE_LINK)
#: Row of the end-effector link in the state's tracked links.
EE_ROW = TRACKED_LINKS.index(EE_LINK)
HAND_RADIUS = 0.08  # metres about the end effector that take in the fingers and most of the hand
#: Joint positions of the "ready" pose (hand 0.49 m above the base, pointing down), rad.
READY = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)
LOWER = np.array([-2.9671, -1.8326, -2.9671, -3.1416, -2.9671, -0.0873, -2.9671])
UPPER = np.array([2.9671, 1.8326, 2.9671, 0.0, 2.9671, 3.8223, 2.9671])
SPEED_LIMIT = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])  # URDF velocity limits, rad/s
EFFORT_LIMIT = np.array([87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0])  # URDF effort limits, N m
CONTROLS = ("joint_velocity", "ee_position")
EE_DOWN = (1.0, 0.0, 0.0, 0.0)  # hand pointing straight down (x, y, z, w)


@dataclass(frozen=True)
class PandaConfig:
    """Control mode and limits.

    Attributes:
        control: "joint_velocity" (7 joint-velocity commands) or "ee_position" (3 end-effector displacements).
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


class PandaArm:
    """Position-controlled Panda: actions become joint targets that pybullet's motors track under the URDF's
    effort limits.

    ``joint_velocity``: a (7,) in [-1, 1] commands ``a * max_joint_speed * limit`` rad/s; the joint targets move
    by that times the control period (a joint-position delta per step), clamped to the joint limits and to
    within two steps' travel of the measured position (a blocked arm does not wind up). ``ee_position``: a (3,)
    in [-1, 1] moves the end-effector target by ``a * max_ee_step`` metres; pybullet's IK (hand pointing down)
    turns it into joint targets.
    """

    name = "panda"
    base_link = "panda_link0"

    def __init__(self, config: PandaConfig | None = None, control_dt: float = 0.05) -> None:
        self.config = c = config or PandaConfig()
        self.control_dt = control_dt
        self.speed = c.max_joint_speed * SPEED_LIMIT
        n = 7 if c.control == "joint_velocity" else 3
        self.action_space = spaces.Box(-1.0, 1.0, shape=(n,), dtype=np.float32)
        f32 = np.float32
        self.spaces = {
            "joint_position": spaces.Box(LOWER.astype(f32), UPPER.astype(f32), dtype=f32),
            "joint_velocity": spaces.Box(-2 * SPEED_LIMIT.astype(f32), 2 * SPEED_LIMIT.astype(f32), dtype=f32),
            "ee_position": spaces.Box(-1.5, 1.5, shape=(3,), dtype=f32),
        }
        self._sim: Sim | None = None
        self._body = -1
        self._target = np.array(READY)
        self._forces = EFFORT_LIMIT.copy()
        self._ee_target = np.zeros(3)

    @property
    def urdf_path(self) -> Path:
        return pybullet_data_file("franka_panda/panda.urdf")

    @property
    def body(self) -> int:
        return self._body

    def load(self, sim: Sim) -> int:
        """Load the URDF with a fixed base at the origin and look up joint and link indices."""
        self._sim = sim
        self._body = sim.load_urdf("robot", self.urdf_path, fixed_base=True)
        sim.hide_from_rays(self._body)
        joints = sim.joint_indices(self._body)
        self._arm = [joints[name] for name in ARM_JOINTS]
        self._fingers = [joints[name] for name in FINGER_JOINTS]
        self.link_index = sim.link_indices(self._body)
        self.link_names = TRACKED_LINKS
        self._tracked = tuple(self.link_index[name] for name in TRACKED_LINKS)
        self._ee = self.link_index[EE_LINK]
        links = sorted(i for i in self.link_index.values() if i >= 0)
        self._nominal = dict(zip(links, sim.inertial_properties(self._body, links)))
        self._dynamics = DynamicsSample()
        self._forces = EFFORT_LIMIT.copy()
        self._all_movable = sorted(self._arm + self._fingers)
        return self._body

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """This episode's link masses (inertias scale with them), friction, restitution and motor strength."""
        if sample == self._dynamics:
            return
        scale_link_dynamics(self._sim, self._body, self._nominal, sample)
        self._forces = EFFORT_LIMIT * sample.motor_scale
        self._dynamics = sample

    def reset_to(self, q: tuple[float, ...]) -> None:
        """Arm at joint positions ``q`` (7,) at rest, fingers half open, motors holding."""
        self._sim.reset_joints(self._body, self._arm, q)
        self._sim.reset_joints(self._body, self._fingers, [FINGER_OPENING] * 2)
        self._sim.forget_contacts(self._body)
        self._target = np.array(q, dtype=float)
        self._sim.set_joint_positions(self._body, self._fingers, [FINGER_OPENING] * 2, [0.0, 0.0], [20.0, 20.0])
        self._hold(np.zeros(7))
        self._ee_target = self._sim.link_frame(self._body, self._ee)[0]

    def _hold(self, velocity: np.ndarray) -> None:
        self._sim.set_joint_positions(self._body, self._arm, self._target.tolist(), velocity.tolist(),
                                      self._forces.tolist())

    def apply_action(self, action: np.ndarray) -> None:
        """Move the joint targets for one control period from a clipped, normalised action."""
        q, _ = self._sim.joint_states(self._body, self._arm)
        if self.config.control == "joint_velocity":
            velocity = np.asarray(action, dtype=float) * self.speed
            travel = 2.0 * self.speed * self.control_dt
            target = np.clip(self._target + velocity * self.control_dt, q - travel, q + travel)
        else:
            ee, _ = self._sim.link_frame(self._body, self._ee)
            self._ee_target = ee + np.asarray(action, dtype=float) * self.config.max_ee_step
            rest = np.concatenate([READY, [FINGER_OPENING] * 2])
            lower = np.concatenate([LOWER, [0.0, 0.0]])
            upper = np.concatenate([UPPER, [0.04, 0.04]])
            solution = self._sim.inverse_kinematics(self._body, self._ee, self._ee_target, EE_DOWN, lower, upper, rest)
            target = solution[[self._all_movable.index(j) for j in self._arm]]
            velocity = (target - q) / self.control_dt
        self._target = np.clip(target, LOWER, UPPER)
        self._hold(np.clip(velocity, -SPEED_LIMIT, SPEED_LIMIT))

    def state(self) -> RobotState:
        """Ground-truth state from two batched pybullet reads (the base is fixed at the origin)."""
        q, dq = self._sim.joint_states(self._body, self._arm)
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
        return state.links.position[EE_ROW]

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """The end effector (world frame, metres) and a radius that takes in the hand's fingers: what the
        ``rgb_array`` view rings and trails, as the point that must reach the target."""
        return self.ee_position(state), HAND_RADIUS

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """Joint positions (rad), joint velocities (rad/s, clipped to twice the limits), end-effector position (m)."""
        space = self.spaces["joint_velocity"]
        return {
            "joint_position": np.clip(state.joint_position, LOWER, UPPER).astype(np.float32),
            "joint_velocity": np.clip(state.joint_velocity, space.low, space.high).astype(np.float32),
            "ee_position": self.ee_position(state).astype(np.float32),
        }
