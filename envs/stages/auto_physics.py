"""``physics="auto"`` as a stage: each episode ticks at what its scene needs
(:func:`clutter_gym.auto_physics.choose_physics`), never below the env's own settings."""

from __future__ import annotations

import weakref
from typing import TYPE_CHECKING

from clutter_gym.auto_physics import choose_physics
from clutter_gym.interfaces import Layout
from clutter_gym.stages.base import Stage

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv


class AutoPhysics(Stage):
    """Sets the env's Sim, ``physics`` and ``substeps`` from each scene, before it is placed."""

    def bind(self, env: ClutterEnv) -> None:
        self._env = weakref.proxy(env)  # no reference cycle: a dropped env is freed at once, its physics server too
        self._base = env.physics

    def scene_chosen(self, scene: Layout) -> None:
        env, base = self._env, self._base
        env.physics = chosen = choose_physics(scene.obstacles, base.physics_hz, base.solver_iterations, env.control_hz)
        if (chosen.physics_hz, chosen.solver_iterations) != (env.sim.physics_hz, env.sim.solver_iterations):
            env.sim.set_physics(chosen.physics_hz, chosen.solver_iterations)
            env.substeps = int(round(chosen.physics_hz / env.control_hz))
