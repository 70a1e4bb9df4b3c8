"""Scripted baselines: reference behaviour to compare learned policies with, and the demo's driver."""

from __future__ import annotations

import math
from collections.abc import Mapping

import gymnasium as gym
import numpy as np

from clutter_gym.robots.wheeled import diffbot

#: metres: the footprint of the base the potential field's influence distance was tuned on
DIFFBOT_FOOTPRINT = diffbot().footprint_radius


class PotentialFieldNavigator:
    """Goal attraction plus LIDAR repulsion (Khatib-style potential field) for ClutterNav.

    The heading is the sum of a unit vector towards the goal and, for every beam closer than ``influence``
    metres, a push away from it weighted by ``1/r - 1/influence``. Angular command = ``turn_gain`` x heading
    error; forward command shrinks with the heading error and with free space ahead. It gets stuck in local
    minima (U-shaped clutter) by design: it is a baseline, not a planner.

    Given ``goal_key="subgoal"`` (an env made with ``subgoal_lookahead > 0``) it steers for the waypoint on the
    shortest path over the known layout instead: a global planner with this field as its local controller, the
    map-based reference a learned policy can be compared with.

    Args:
        lidar_angles: beam angles in the robot frame, radians (None: goal seeking only).
        lidar_range: metres, to undo the observation's normalisation.
        influence: distance below which obstacles repel, metres.
        repulsion: weight of the repulsive sum relative to the unit goal vector.
        turn_gain: angular command per radian of heading error.
        goal_key: the observation entry to steer for, ``"goal"`` or ``"subgoal"``.
        forward_only: the env drives forwards only (``reverse=False``): its linear action -1..1 means stand..full
            speed, and the field's speed fraction is mapped onto it, so it drives the same either way.
    """

    def __init__(
        self,
        lidar_angles: np.ndarray | None,
        lidar_range: float,
        influence: float = 0.5,
        repulsion: float = 0.1,
        turn_gain: float = 1.5,
        goal_key: str = "goal",
        forward_only: bool = False,
    ) -> None:
        if goal_key not in ("goal", "subgoal"):
            raise ValueError(f"goal_key must be 'goal' or 'subgoal', got {goal_key!r}")
        self.angles = None if lidar_angles is None else np.asarray(lidar_angles, dtype=float)
        self.lidar_range = lidar_range
        self.influence, self.repulsion, self.turn_gain = influence, repulsion, turn_gain
        self.goal_key = goal_key
        self.forward_only = forward_only

    @classmethod
    def for_env(cls, env: gym.Env, goal_key: str = "goal") -> PotentialFieldNavigator:
        """Configured from a ClutterNav env's LIDAR (or goal seeking only when it has none).

        Raises:
            ValueError: ``goal_key`` is not an entry of the env's observations.
        """
        if goal_key not in env.observation_space.spaces:
            raise ValueError(f"the env has no {goal_key!r} observation"
                             + (" (make it with subgoal_lookahead > 0)" if goal_key == "subgoal" else ""))
        lidar = next((s for s in env.unwrapped.sensors if s.name == "lidar"), None)
        forward_only = bool(getattr(env.unwrapped, "forward_only", False))
        if lidar is None:
            return cls(None, 1.0, goal_key=goal_key, forward_only=forward_only)
        # obstacles repel from the same gap beyond the footprint as for the diffbot the field was tuned on
        influence = 0.5 + (env.unwrapped.robot.config.footprint_radius - DIFFBOT_FOOTPRINT)
        return cls(lidar.config.angles, lidar.config.max_range, influence=influence, goal_key=goal_key,
                   forward_only=forward_only)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        return self.command(*self.steer(obs))

    #: what the action entries -1..1 of a policy picking this field's waypoint span: its bearing, radians
    waypoint_scales = (math.pi,)

    def toward(self, obs: Mapping[str, np.ndarray], bearing: float) -> np.ndarray:
        """The action steering for a waypoint at ``bearing`` (radians from the robot's heading, counter-clockwise)
        instead of the direction the goal entry gives; the LIDAR's push and the speed rule are the field's."""
        bearing = min(max(bearing, -math.pi + 1e-6), math.pi - 1e-6)  # straight behind: left for +pi, right for -pi
        target = np.array(obs[self.goal_key], dtype=float)
        target[1], target[2] = math.sin(bearing), math.cos(bearing)
        return self({**obs, self.goal_key: target})

    def steer(self, obs: Mapping[str, np.ndarray]) -> tuple[float, float]:
        """``(heading error, free space ahead)``: the angle (radians, counter-clockwise positive) from the robot's
        heading to the field's direction, and the speed fraction the LIDAR's returns within 30 degrees of ahead
        allow."""
        sin_b, cos_b = (float(v) for v in obs[self.goal_key][1:3])
        heading = np.array([cos_b, sin_b])
        ahead = 1.0
        if self.angles is not None and "lidar" in obs:
            ranges = np.asarray(obs["lidar"], dtype=float) * self.lidar_range
            close = ranges < self.influence
            push = (1.0 / np.maximum(ranges[close], 1e-3) - 1.0 / self.influence)
            angles = self.angles[close]
            heading -= self.repulsion * np.array([push @ np.cos(angles), push @ np.sin(angles)])
            front = np.abs(self.angles) < math.radians(30)
            ahead = float(np.clip((ranges[front].min() - 0.2) / 0.6, 0.0, 1.0)) if front.any() else 1.0
        return math.atan2(heading[1], heading[0]), ahead

    def command(self, error: float, ahead: float) -> np.ndarray:
        """The action for a heading ``error`` (radians; beyond pi it turns the long way round) and the speed
        fraction ``ahead`` allows."""
        angular = float(np.clip(self.turn_gain * error, -1.0, 1.0))
        linear = float(np.clip(math.cos(error), 0.0, 1.0)) * max(ahead, 0.15)
        if self.forward_only:
            linear = 2.0 * linear - 1.0
        return np.array([linear, angular], dtype=np.float32)


class StraightLineReacher:
    """Scripted IK for ClutterReach: the end effector heads straight for the target, as fast as allowed.

    With ``control="ee_position"`` each action is the displacement towards the target, in units of
    ``max_ee_step`` and clipped to [-1, 1]; pybullet's IK turns it into joint targets. It ignores the clutter
    entirely, so it measures how often the straight line is free: a learned policy should beat it on contacts.
    """

    def __init__(self, max_ee_step: float) -> None:
        self.max_ee_step = max_ee_step

    @classmethod
    def for_env(cls, env: gym.Env) -> StraightLineReacher:
        """Configured from a ClutterReach env made with ``control="ee_position"``.

        Raises:
            ValueError: the env has another action space (joint-velocity control).
        """
        config = getattr(env.unwrapped.robot, "config", None)
        if getattr(config, "control", None) != "ee_position":
            raise ValueError("StraightLineReacher needs a ClutterReach env made with control='ee_position'")
        return cls(config.max_ee_step)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        offset = np.asarray(obs["target"], dtype=float) - np.asarray(obs["ee_position"], dtype=float)
        return np.clip(offset / self.max_ee_step, -1.0, 1.0).astype(np.float32)


class ProximityFieldReacher:
    """A joint-space potential field for ClutterReach that reads only what the arm itself measures (Khatib, 1986).

    The end effector is drawn straight at the target at ``attraction`` (m/s per metre of offset, capped at
    ``top_speed``), through damped least squares on the arm's own kinematic model at its measured joint
    positions; every link that its proximity reading (the env's ``clearance`` and ``clearance_direction``, as a
    proximity skin would give them) puts closer than ``influence`` to an obstacle is pushed away from it through
    that link's Jacobian, by ``repulsion`` x (influence - distance) / influence. It ignores the hand's orientation
    and stops in local minima, most often in front of a shelf compartment that its hand, pointing down, does not
    fit into. It needs joint-velocity control and ``observe_directions=True``.

    Args:
        max_joint_speed: the env's action scale, a fraction of each joint's URDF velocity limit.
        attraction: end-effector speed per metre from the target, 1/s.
        top_speed: cap on the end effector's commanded speed, m/s.
        influence: proximity below which a link is pushed away, metres.
        repulsion: the push's strength at contact, m/s along the obstacle's direction, mapped onto the joints
            through the link's Jacobian transpose.
        damping: damped-least-squares damping, metres.
    """

    #: Per proximity reading (the env's tracked links, in order): the two frames whose midpoint stands for the
    #: link's surface, and how many arm joints move it.
    POINTS = (*((f"panda_link{i}", f"panda_link{i + 1}", i) for i in range(1, 7)),
              ("panda_link7", "panda_hand", 7), ("panda_hand", "panda_grasptarget", 7),
              ("panda_grasptarget", "panda_grasptarget", 7), ("panda_grasptarget", "panda_grasptarget", 7))

    def __init__(self, max_joint_speed: float, attraction: float = 2.0, top_speed: float = 0.3,
                 influence: float = 0.08, repulsion: float = 10.0, damping: float = 0.05) -> None:
        from clutter_gym.robots.panda import SPEED_LIMIT, PandaArm
        from clutter_gym.urdf.kinematics import UrdfKinematics

        if not attraction > 0.0:
            raise ValueError(f"attraction must be > 0 (1/s), got {attraction!r}")
        self.kinematics = UrdfKinematics(PandaArm().urdf_path)
        self.speed_scale = max_joint_speed * SPEED_LIMIT
        self.attraction, self.top_speed, self.influence = attraction, top_speed, influence
        self.repulsion, self.damping = repulsion, damping

    @classmethod
    def for_env(cls, env: gym.Env, **gains: float) -> ProximityFieldReacher:
        """Configured from a ClutterReach env made with ``observe_directions=True`` and joint-velocity control.

        Raises:
            ValueError: the env has another control mode, or no ``clearance_direction`` observation.
        """
        config = getattr(env.unwrapped.robot, "config", None)
        if getattr(config, "control", None) != "joint_velocity":
            raise ValueError("ProximityFieldReacher needs a ClutterReach env with control='joint_velocity'")
        if env.unwrapped.robot.name != "panda":
            raise ValueError(f"ProximityFieldReacher pushes on the Panda's links; the env drives "
                             f"{env.unwrapped.robot.name!r} (JointPlannerReacher plans for any arm)")
        if "clearance_direction" not in env.observation_space.spaces:
            raise ValueError("ProximityFieldReacher needs a ClutterReach env made with observe_directions=True")
        return cls(config.max_joint_speed, **gains)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        """Joint-velocity actions in [-1, 1] for one observation (7,) or a batch (n, 7)."""
        from clutter_gym.planning.joint_space import point_jacobian
        from clutter_gym.robots.panda import EE_LINK, FINGER_OPENING

        single = np.ndim(obs["target"]) == 1
        q = np.atleast_2d(np.asarray(obs["joint_position"], dtype=float))
        frames = self.kinematics.forward(np.concatenate([q, np.full((len(q), 2), FINGER_OPENING)], axis=1))
        ee = frames[EE_LINK][:, :3, 3]
        wanted = _capped(self.attraction * (np.atleast_2d(obs["target"]) - ee), self.top_speed)
        jac = point_jacobian(self.kinematics, frames, ee)
        gram = jac @ jac.transpose(0, 2, 1) + self.damping**2 * np.eye(3)
        rates = np.einsum("nji,nj->ni", jac, np.linalg.solve(gram, wanted[..., None])[..., 0])
        distance = np.atleast_2d(obs["clearance"])
        direction = np.asarray(obs["clearance_direction"], dtype=float).reshape(len(q), -1, 3)
        for k, (link, beyond, moved_by) in enumerate(self.POINTS):
            near = (distance[:, k] < self.influence) & (np.linalg.norm(direction[:, k], axis=1) > 0.5)
            if not near.any():
                continue
            point = 0.5 * (frames[link][:, :3, 3] + frames[beyond][:, :3, 3])
            strength = self.repulsion * near * (self.influence - distance[:, k]) / self.influence
            push = -direction[:, k] * strength[:, None]
            rates += np.einsum("nji,nj->ni", point_jacobian(self.kinematics, frames, point, moved_by), push)
        action = np.clip(rates / self.speed_scale, -1.0, 1.0).astype(np.float32)
        return action[0] if single else action


class CascadedFlyer:
    """A cascaded position controller for ClutterFly's rate actions: the way a flight stack's position mode flies.

    The target point (``obs[goal_key]``, body frame) sets a velocity towards it (``position_gain`` x the offset, at
    most ``max_speed``), the velocity error an acceleration (``velocity_gain`` x error, at most ``max_accel``), and
    that acceleration plus gravity the thrust vector: its length along body z is the collective thrust, and body
    rates ``attitude_gain`` x (body z cross the thrust direction) tilt the airframe onto it. Yaw is held, or turned
    with ``yaw_gain``. It reads only the observation (target offset, ``velocity``, ``attitude``, and
    ``thrust_ratio`` where the env gives it: its hover thrust is then the airframe's estimated one, not the
    datasheet's), as a policy would, one or a batch (rows).
    Without obstacle sensing it flies straight at its target: with ``goal_key="goal"`` a mapless reference that
    meets every obstacle on the line; with ``"subgoal"`` (an env made with ``subgoal_lookahead > 0``) the map-based
    planner reference, and the pursuit a residual ClutterFly policy adds its actions to.

    Args:
        hover_thrust: collective thrust of a level hover as a fraction of the maximum.
        rate_scale: body rates (rad/s) of action +1 about x, y, z.
        gravity: m/s^2.
        goal_key: ``"goal"`` or ``"subgoal"``.
        position_gain: commanded speed per metre of offset, 1/s.
        velocity_gain: commanded acceleration per m/s of velocity error, 1/s.
        max_speed: m/s.
        max_accel: m/s^2.
        attitude_gain: body rate per radian of tilt error, 1/s.
        yaw_gain: 0 holds the yaw; > 0 turns the nose (body x, where the LIDAR and the camera look) towards the
            horizontal velocity it wants, at this yaw rate per radian of bearing, 1/s.
    """

    def __init__(self, hover_thrust: float, rate_scale: tuple[float, float, float], gravity: float,
                 goal_key: str = "goal", position_gain: float = 1.5, velocity_gain: float = 3.0,
                 max_speed: float = 1.0, max_accel: float = 4.0, attitude_gain: float = 6.0,
                 yaw_gain: float = 0.0) -> None:
        if goal_key not in ("goal", "subgoal"):
            raise ValueError(f"goal_key must be 'goal' or 'subgoal', got {goal_key!r}")
        self.hover_thrust, self.rate_scale, self.gravity = hover_thrust, np.asarray(rate_scale, float), gravity
        self.goal_key = goal_key
        self.position_gain, self.velocity_gain = position_gain, velocity_gain
        self.max_speed, self.max_accel, self.attitude_gain = max_speed, max_accel, attitude_gain
        self.yaw_gain = yaw_gain

    @classmethod
    def for_env(cls, env: gym.Env, goal_key: str = "goal", **gains: float) -> CascadedFlyer:
        """Configured from a ClutterFly env's quadrotor (rate control).

        Raises:
            ValueError: the env is not a rate-controlled ClutterFly, or has no ``goal_key`` observation.
        """
        robot = env.unwrapped.robot
        if getattr(getattr(robot, "config", None), "control", None) != "rates" or not hasattr(robot, "hover_action"):
            raise ValueError("CascadedFlyer needs a ClutterFly env with rate control")
        if goal_key not in env.observation_space.spaces:
            raise ValueError(f"the env has no {goal_key!r} observation"
                             + (" (make it with subgoal_lookahead > 0)" if goal_key == "subgoal" else ""))
        return cls._for_robot(robot, env.unwrapped.sim.gravity, goal_key, **gains)

    @classmethod
    def nominal(cls, goal_key: str = "subgoal", **gains: float) -> CascadedFlyer:
        """Configured for ClutterFly's quadrotor as every ClutterFly env builds it (no env needed)."""
        from clutter_gym.robots import Quadrotor
        from clutter_gym.sim import GRAVITY

        return cls._for_robot(Quadrotor(), GRAVITY, goal_key, **gains)

    @classmethod
    def _for_robot(cls, robot, gravity: float, goal_key: str, **gains: float) -> CascadedFlyer:
        c = robot.config
        hover = 0.5 * (float(robot.hover_action(gravity)[0]) + 1.0)
        return cls(hover, (c.max_roll_rate, c.max_pitch_rate, c.max_yaw_rate), gravity, goal_key, **gains)

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        return self.track(self.velocity(obs), obs)

    def velocity(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        """The outer loop: the velocity it commands towards its target (m/s, body frame; one or a batch)."""
        offset = np.asarray(obs[self.goal_key], dtype=float)[..., :3]
        return _capped(self.position_gain * offset, self.max_speed)

    def track(self, wanted: np.ndarray, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        """The action that flies velocity ``wanted`` (m/s, body frame; one or a batch of rows): the controller's
        inner loops, for a caller that sets the velocity itself."""
        velocity = np.asarray(obs["velocity"], dtype=float)[..., :3]
        up = np.asarray(obs["attitude"], dtype=float)
        accel = _capped(self.velocity_gain * (wanted - velocity), self.max_accel)
        thrust = accel + self.gravity * up  # the specific force the rotors must give, body frame
        direction = thrust / np.maximum(np.linalg.norm(thrust, axis=-1, keepdims=True), 1e-9)
        hover = self.hover_thrust
        if "thrust_ratio" in obs:  # the airframe's own hover thrust, from the flight controller's estimate
            hover = hover / np.asarray(obs["thrust_ratio"], dtype=float)
        collective = hover * thrust[..., 2:3] / self.gravity
        yaw = np.zeros_like(up[..., 0])
        if self.yaw_gain:  # turn body x (where the LIDAR and the camera look) towards the horizontal velocity wanted
            horizontal = np.linalg.norm(wanted[..., :2], axis=-1)
            yaw = np.where(horizontal > 0.2, self.yaw_gain * np.arctan2(wanted[..., 1], wanted[..., 0]), 0.0)
        tilt = self.attitude_gain * np.stack([-direction[..., 1], direction[..., 0]], axis=-1)  # body z onto thrust
        rates = np.concatenate([tilt, yaw[..., None]], axis=-1)
        action = np.concatenate([2.0 * collective - 1.0, rates / self.rate_scale], axis=-1)
        return np.clip(action, -1.0, 1.0).astype(np.float32)


def _capped(vectors: np.ndarray, bound: float) -> np.ndarray:
    """Each vector (last axis) scaled down to length ``bound`` if longer."""
    norm = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors * np.minimum(1.0, bound / np.maximum(norm, 1e-12))
