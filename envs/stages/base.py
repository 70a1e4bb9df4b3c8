"""The stage contract: optional work in an env's step, declared by the hooks it overrides.

A stage is one feature an env may or may not have (the collision monitor, the action noise channel, movable
obstacles, the near field, ``physics="auto"``, the render trail). The core (``clutter_gym.core``) calls, at each
point of the step, only the hooks that the stages active this episode override, so an env pays nothing on its hot
path for a feature it does not have, and adding a feature adds a stage, not a branch in the core. Hooks, in the
order the core calls them:

- reset: :meth:`Stage.bind` once, when the env is built; :meth:`Stage.scene_chosen` before the scene is placed;
  :meth:`Stage.episode_start` after it is, which says whether the stage has work in this episode's steps;
  :meth:`Stage.checked` after the first collision check;
- step: :meth:`Stage.command` (the policy's action as the command the reward and the monitor see),
  :meth:`Stage.actuate` (the command on its way to the motors), the physics, :meth:`Stage.physics_done`, the
  collision check, :meth:`Stage.checked`, the observation, :meth:`Stage.step_info`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.datatypes import Obstacle, RobotState
from clutter_gym.interfaces import Layout

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv

#: the hooks a stage may override, in the order a step calls them (the reset's first)
HOOKS = ("scene_chosen", "episode_start", "command", "actuate", "physics_done", "checked", "step_info")


class Stage:
    """One optional feature of an env's step; every hook does nothing unless a subclass overrides it."""

    def bind(self, env: ClutterEnv) -> None:
        """Take what the stage reads from the built env (its parts, not its episode state)."""

    def scene_chosen(self, scene: Layout) -> None:
        """The episode's scene is chosen and not yet placed."""

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        """The scene is placed (``obstacles`` and their pybullet ``bodies``, in scene order) and the robot stands at
        its start; ``rng`` is the episode's noise generator. Returns whether this episode's steps call the stage."""
        return True

    def command(self, action: np.ndarray) -> np.ndarray:
        """The checked policy action as the normalised command to drive (what the reward and monitor see)."""
        return action

    def actuate(self, command: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The command on its way to the motors (the reward keeps the one :meth:`command` gave)."""
        return command

    def physics_done(self) -> None:
        """The physics has ticked; the robot's state is not read yet."""

    def checked(self, state: RobotState) -> None:
        """The collision check of ``state`` is done (at reset and after every step)."""

    def step_info(self, info: dict[str, Any]) -> None:
        """Add the stage's entries to the step's ``info``."""


def hooks(stages: Sequence[Stage], name: str) -> tuple[Callable[..., Any], ...]:
    """The bound ``name`` hooks of the ``stages`` that override it, in order."""
    default = getattr(Stage, name)
    return tuple(getattr(stage, name) for stage in stages if getattr(type(stage), name) is not default)
