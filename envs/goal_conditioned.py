"""ClutterReach as a goal-conditioned env, for hindsight experience replay (HER): ``ClutterReachGoal-v1``.

panda-gym's envs and SB3's ``HerReplayBuffer`` expect a ``Dict`` observation with ``observation``,
``achieved_goal`` and ``desired_goal`` entries and a ``compute_reward(achieved_goal, desired_goal, info)`` that
gives the reward of any goal, in batches, so that a stored transition can be relabelled with a goal the arm did
reach. The goal part of the reward must then depend on the two goals alone: here it is panda-gym's, ``-1`` while
the end effector is farther than the success radius from the goal (``reward_type="sparse"``) or minus that
distance (``"dense"``), and it replaces ClutterReach's ``progress`` and ``success`` terms, which depend on the
previous step. The safety and effort terms (``contact``, ``self_contact``, ``clearance``, ``tunneling``,
``control``) do not depend on the goal; they come from the step's ``info["reward_terms"]`` and are added
unchanged, so relabelled transitions keep their penalties (SB3's ``HerReplayBuffer`` then needs
``copy_info_dict=True``, which stores each step's info for ``compute_reward``). ``step`` returns
``compute_reward`` of its own transition, so the two always agree. Episodes end as ClutterReach's do (on success,
in the env's own terms).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

from clutter_gym.clutter_reach import ClutterReachEnv

#: ClutterReach's reward terms that the goal reward replaces.
GOAL_TERMS = ("progress", "success")
REWARD_TYPES = ("sparse", "dense")


class ClutterReachGoalEnv(ClutterReachEnv):
    """ClutterReach with the ``Dict(observation, achieved_goal, desired_goal)`` observation of goal-conditioned envs:
    ``achieved_goal`` is ``ee_position``, ``desired_goal`` is ``target`` (world frame, metres) and ``observation``
    the other entries flattened (``ee_position`` included, as panda-gym does).

    It is the env itself, not a wrapper, so that ``env.unwrapped.compute_reward`` is there, where
    Gymnasium-Robotics' ``GoalEnv`` puts it and HER implementations call it. It takes ClutterReach's keyword
    arguments (:class:`~clutter_gym.clutter_reach.ClutterReachEnv`) and ``reward_type``: "sparse" (-1 until within
    the success radius, else 0) or "dense" (minus the distance).
    """

    def __init__(self, reward_type: str = "sparse", **kwargs: Any) -> None:
        if reward_type not in REWARD_TYPES:
            raise ValueError(f"reward_type must be one of {REWARD_TYPES}, got {reward_type!r}")
        super().__init__(**kwargs)
        self.reward_type = reward_type
        self.distance_threshold = float(self.task.success_radius)
        inner = self.observation_space
        self._rest = spaces.Dict({key: space for key, space in inner.spaces.items() if key != "target"})
        goal = inner["target"]
        self.observation_space = spaces.Dict({
            "observation": spaces.flatten_space(self._rest),
            "achieved_goal": spaces.Box(goal.low, goal.high, dtype=np.float32),
            "desired_goal": goal,
        })

    def _goal_obs(self, obs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        return {
            "observation": spaces.flatten(self._rest, {key: obs[key] for key in self._rest.spaces}).astype(np.float32),
            "achieved_goal": np.asarray(obs["ee_position"], dtype=np.float32),
            "desired_goal": np.asarray(obs["target"], dtype=np.float32),
        }

    def reset(self, *, seed: int | None = None,
              options: Mapping[str, Any] | None = None) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        obs, info = super().reset(seed=seed, options=options)
        return self._goal_obs(obs), info

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        obs, _, terminated, truncated, info = super().step(action)
        goal_obs = self._goal_obs(obs)
        reward = float(self.compute_reward(goal_obs["achieved_goal"], goal_obs["desired_goal"], info))
        return goal_obs, reward, terminated, truncated, info

    def compute_reward(self, achieved_goal: np.ndarray, desired_goal: np.ndarray,
                       info: Mapping[str, Any] | Sequence[Mapping[str, Any]] | np.ndarray) -> np.ndarray:
        """The reward of reaching ``achieved_goal`` when ``desired_goal`` was asked for, with the goal-free terms of
        ``info``'s step; for one transition (goals of shape (3,), one info) or a batch ((n, 3), n infos).

        Returns:
            float32 reward(s), shape () or (n,).
        """
        distance = np.linalg.norm(np.asarray(achieved_goal) - np.asarray(desired_goal), axis=-1)
        if self.reward_type == "sparse":
            goal = -(distance > self.distance_threshold).astype(np.float32)
        else:
            goal = -distance.astype(np.float32)
        infos = [info] if isinstance(info, Mapping) else list(info)
        if not all("reward_terms" in i for i in infos):
            raise ValueError("compute_reward needs the info of each transition's step (its reward_terms hold the "
                             "contact and effort penalties); with SB3 pass "
                             "replay_buffer_kwargs={'copy_info_dict': True} to HerReplayBuffer")
        rest = np.array([sum(v for k, v in i["reward_terms"].items() if k not in GOAL_TERMS) for i in infos],
                        dtype=np.float32)
        return (goal + (rest[0] if isinstance(info, Mapping) else rest)).astype(np.float32)


# The keyword check every env runs at make time (make_checks.check_keywords) reads __init__'s signature: ClutterReach's
# arguments and reward_type, so a misspelt one is named with its closest match as for every env.
_reach = inspect.signature(ClutterReachEnv.__init__)
ClutterReachGoalEnv.__init__.__signature__ = _reach.replace(  # type: ignore[attr-defined]
    parameters=[*_reach.parameters.values(),
                inspect.Parameter("reward_type", inspect.Parameter.KEYWORD_ONLY, default="sparse", annotation=str)])
