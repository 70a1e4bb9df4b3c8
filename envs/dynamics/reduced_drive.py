"""A differential drive moved by its reduced model (:mod:`clutter_gym.dynamics.drive_model`) while nothing is within
a control step's reach, and by full physics otherwise.

After each collision check the part decides how the next step runs. The base cannot move any of its points further
than ``(max_linear_speed + max_angular_speed * footprint_radius) / control_hz`` in one step (the model never exceeds
its commands), so while the clearance FCL measures exceeds that reach and the contact tolerance, no contact can
begin within the step, and pybullet is not stepped. Otherwise the robot's pybullet body takes the model's pose,
velocity and wheel speeds, and the step runs under full physics; with ``handover="step"`` the model takes the base
back once the clearance exceeds the reach by :data:`RETURN_MARGIN` again, with ``handover="episode"`` full physics
keeps it to the episode's end. An episode whose scene has a movable obstacle runs under full physics throughout.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from clutter_gym.datatypes import CollisionReport, DynamicsSample, LinkStates, Obstacle, RobotState
from clutter_gym.dynamics.base import Dynamics, FullPhysics
from clutter_gym.dynamics.drive_fit import DriveFit
from clutter_gym.dynamics.drive_model import LEFT, LEFT_ROLLED, RIGHT, RIGHT_ROLLED, STATE_SIZE, YAW, X, Y, drive_ticks
from clutter_gym.robots.diffdrive import DiffDriveRobot
from clutter_gym.sim import Sim
from clutter_gym.util.transforms import quat_multiply, yaw_quat

#: m, the clearance beyond the reach at which the model takes the base back from full physics (no chatter)
RETURN_MARGIN = 0.05
#: the model takes the base back only while it stands upright within this tilt (cos of 5 degrees)
UPRIGHT = math.cos(math.radians(5.0))
HANDOVERS = ("step", "episode")


class ReducedDrive(Dynamics):
    """See the module docstring.

    Attributes:
        full: whether the next step runs under full physics.
        reduced_steps, full_steps: the steps run under each since the env was made.
    """

    def __init__(self, sim: Sim, robot: DiffDriveRobot, fit: DriveFit, control_hz: float, contact_tolerance: float,
                 handover: str = "step", reason: str = "") -> None:
        if handover not in HANDOVERS:
            raise ValueError(f"handover must be one of {HANDOVERS}, got {handover!r}")
        self.sim, self.robot, self.fit, self.handover, self.reason = sim, robot, fit, handover, reason
        self.physics = FullPhysics(sim, robot, reason)
        c = robot.config
        self.reach = (c.max_linear_speed + c.max_angular_speed * c.footprint_radius) / control_hz
        self.tolerance = contact_tolerance
        self.full, self._episode_full = True, True
        self.reduced_steps = self.full_steps = 0
        self._model = np.zeros(STATE_SIZE)
        self._array = fit.params.as_array()
        self._last: RobotState | None = None

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """The robot's links take the sample (for the steps under full physics), and the model's acceleration limit
        scales with the motors' strength over the mass, capped by the floor's grip times the friction's scale."""
        self.physics.apply_dynamics(sample)
        p = self.fit.params
        torque = p.acceleration * sample.motor_scale / sample.mass_scale
        grip = max(self.fit.grip, p.acceleration) * sample.friction_scale
        self._array = p.as_array(min(torque, grip) / p.acceleration)

    def episode_start(self, obstacles: Sequence[Obstacle]) -> dict[str, object]:
        state = self.robot.state()
        rotation = state.rotation
        yaw = state.yaw
        self._height = float(state.position[2])
        # the base's rest attitude without its heading, and each tracked link's pose in the base frame
        self._rest = _yaw_matrix(-yaw) @ rotation
        self._rest_quat = tuple(Rotation.from_matrix(self._rest).as_quat())
        self._link_offsets = (state.links.position - state.position) @ rotation
        self._link_rotations = np.einsum("ji,njk->nik", rotation, state.links.rotation)
        self._model[:] = (state.position[0], state.position[1], yaw, 0.0, 0.0, 0.0, 0.0)
        robot = self.robot
        self._wheels = robot.wheel_joints
        self._n_left = len(robot.base.left_wheels)
        self._wheel_angles = self.sim.actuation.joint_states(robot.body, self._wheels)[0]
        movable = any(o.movable for o in obstacles)
        self._episode_full = self.full = movable
        self._last = state
        if movable:
            return {"model": "physics", "reason": "a movable obstacle in the scene: full physics for the episode"}
        return {"model": "reduced", "reason": self.reason, "fit_error": round(self.fit.error, 4)}

    def advance(self, command: np.ndarray, substeps: int) -> None:
        if self.full:
            self.full_steps += 1
            self.physics.advance(command, substeps)
            return
        self.reduced_steps += 1
        c = self.robot.config
        left, right = self.fit.params.sides(float(command[0]) * c.max_linear_speed,
                                            float(command[1]) * c.max_angular_speed)
        m = self._model
        rolled = m[LEFT_ROLLED], m[RIGHT_ROLLED]
        drive_ticks(m, left, right, self._array, 1.0 / self.sim.physics_hz, substeps)
        self._turn_wheels(m[LEFT_ROLLED] - rolled[0], m[RIGHT_ROLLED] - rolled[1])
        if self.sim.visuals:  # a camera or a rendered frame shows the robot where the model has it
            position, rotation, _, _ = self._pose()
            self.sim.set_pose(self.robot.body, position + rotation @ self.robot.com_offset, self._quat())

    def state(self) -> RobotState:
        if self.full:
            self._last = self.physics.state()
            return self._last
        position, rotation, v, w = self._pose()
        heading = rotation[:, 0] * v
        offsets = self._link_offsets @ rotation.T
        com = rotation @ self.robot.com_offset
        swirl = np.empty_like(offsets)  # (0, 0, w) x each offset
        swirl[:, 0], swirl[:, 1], swirl[:, 2] = -w * offsets[:, 1], w * offsets[:, 0], 0.0
        spin = np.zeros_like(offsets)
        spin[:, 2] = w
        links = LinkStates(position=position + offsets, rotation=np.matmul(rotation, self._link_rotations),
                           linear_velocity=heading + swirl, angular_velocity=spin)
        last = self._last
        assert last is not None
        self._last = RobotState(position=position, rotation=rotation,
                                linear_velocity=(heading[0] - w * com[1], heading[1] + w * com[0], 0.0),
                                angular_velocity=(0.0, 0.0, w), links=links, link_names=last.link_names,
                                link_index=last.link_index, body=last.body)
        return self._last

    def contacts(self) -> list[tuple[int, float]]:
        # a reduced step began farther than its reach from everything: pybullet, not stepped, has no new contact
        return self.physics.contacts() if self.full else []

    def checked(self, report: CollisionReport) -> None:
        if self._episode_full:
            return
        clearance = report.min_clearance
        if not self.full and clearance < self.reach + self.tolerance:
            self._to_physics()
        elif self.full and self.handover == "step" and clearance > self.reach + self.tolerance + RETURN_MARGIN:
            last = self._last
            assert last is not None
            if last.rotation[2, 2] > UPRIGHT:
                self._from_physics(last)

    # ------------------------------------------------------------------------------------------ hand-over
    def _pose(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """(base origin, rotation, forward speed, yaw rate) of the model's state."""
        m = self._model
        v, w = self.fit.params.body(m[LEFT], m[RIGHT])
        return np.array([m[X], m[Y], self._height]), _yaw_matrix(m[YAW]) @ self._rest, v, w

    def _turn_wheels(self, left: float, right: float) -> None:
        """Roll the pybullet body's wheels by the distances ``left`` and ``right`` (m) they rolled over the step, and
        set their speeds to the model's: the encoders (the odometry sensor) read them, and full physics takes them
        over at a hand-over."""
        n, radius, m = self._n_left, self.robot.config.wheel_radius, self._model
        angles = self._wheel_angles
        angles[:n] += left / radius
        angles[n:] += right / radius
        p = self.fit.params
        mean, half = 0.5 * (m[LEFT] + m[RIGHT]), 0.5 * p.wheel_track * (m[RIGHT] - m[LEFT]) / p.track
        speeds = [(mean - half) / radius] * n + [(mean + half) / radius] * (len(angles) - n)
        self.sim.actuation.reset_joints(self.robot.body, self._wheels, angles.tolist(), speeds)

    def _quat(self) -> tuple[float, float, float, float]:
        return quat_multiply(yaw_quat(float(self._model[YAW])), self._rest_quat)

    def _to_physics(self) -> None:
        """The robot's pybullet body takes the model's pose, velocity and wheel speeds; full physics runs from the
        next step."""
        position, rotation, v, w = self._pose()
        robot, sim, body = self.robot, self.sim, self.robot.body
        com = rotation @ robot.com_offset
        sim.set_pose(body, position + com, self._quat())
        sim.set_base_velocity(body, (rotation[:, 0] * v + np.cross((0.0, 0.0, w), com)).tolist(), (0.0, 0.0, w))
        sim.record.forget_contacts(body)
        robot.release_hold()
        self.full = True

    def _from_physics(self, state: RobotState) -> None:
        """The model takes the base's pose and speeds from full physics; the next step runs under it."""
        rotation = state.rotation
        lin, ang = state.linear_velocity, state.angular_velocity
        v = float(rotation[:, 0] @ lin)
        w = float(rotation[:, 2] @ ang)
        p = self.fit.params
        left, right = p.sides(v / max(1e-6, 1.0 - p.scrub * abs(w)), w)
        self._model[:] = (state.position[0], state.position[1], state.yaw, left, right, 0.0, 0.0)
        self._wheel_angles = self.sim.actuation.joint_states(self.robot.body, self._wheels)[0]
        self.full = False


def _yaw_matrix(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
