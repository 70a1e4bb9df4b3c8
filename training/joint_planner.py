"""The map-based reference for ClutterReach: plan on the known layout at every reset, then track the path.

It answers "how often does the layout allow a clean reach at all?", an upper bound for a policy that acts from the
same map. The planning (IK goals, RRT-Connect, shortcutting) is :mod:`clutter_gym.planning.joint_space`; this
module turns its path into the env's joint-velocity actions.
"""

from __future__ import annotations

from collections.abc import Mapping

import gymnasium as gym
import numpy as np

from clutter_gym.planning.joint_space import ArmPlanner, time_parameterise


class JointPlannerReacher:
    """The map-based reference for ClutterReach (``control="joint_velocity"``): plan on the known layout at
    every reset, then track the path.

    The tracker time-parameterises the path at the env's joint speed limits and commands, each step, the
    velocity that brings the measured joints to the next reference point. Without a plan (no IK solution clear
    of the layout, or RRT-Connect out of nodes) the arm holds still: the episode times out, and :attr:`no_plan`
    says so.

    Args:
        env: a ClutterReach env (its scene and joint speeds are read from it at every reset).
        margin: planning clearance, metres.
        fidelity: the collision fidelity the planner checks at.
        seed: the planner's random stream (goal seeds, samples, shortcuts).

    Raises:
        ValueError: the env is not under joint-velocity control.
    """

    def __init__(self, env: gym.Env, margin: float = 0.02, fidelity: str = "convex", seed: int = 0) -> None:
        base = env.unwrapped
        config = getattr(base.robot, "config", None)
        if getattr(config, "control", None) != "joint_velocity":
            raise ValueError("JointPlannerReacher needs a ClutterReach env made with control='joint_velocity'")
        self.env = base
        self.planner = ArmPlanner(margin, fidelity, base.robot.model)
        self.rng = np.random.default_rng(seed)
        self.speed = base.robot.speed * base.robot.control_dt  # rad per step at an action of 1
        self._scene = None
        self.reference: np.ndarray | None = None
        self._k = 0
        self.planned = self.failed = 0

    def _new_episode(self) -> None:
        scene = self.env.scene
        path = self.planner.plan(scene.obstacles, np.array(scene.start), np.array(scene.target), self.rng)
        self.planned += path is not None
        self.failed += path is None
        self.reference = None if path is None else time_parameterise(path, self.speed)
        self._scene, self._k = scene, 0

    @property
    def no_plan(self) -> str | None:
        """Why the arm holds still this episode ("the planner found no path"), or None while it has a plan (and
        before the episode's first action, which plans)."""
        return "the planner found no path" if self._scene is not None and self.reference is None else None

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        if self.env.scene is not self._scene:
            self._new_episode()
        if self.reference is None:
            return np.zeros(self.planner.n_joints, dtype=np.float32)
        self._k = min(self._k + 1, len(self.reference) - 1)
        q = np.asarray(obs["joint_position"], dtype=float)
        return np.clip((self.reference[self._k] - q) / self.speed, -1.0, 1.0).astype(np.float32)
