"""Step stages: the optional work of an env's step, each a :class:`Stage` with hooks around the physics
(:mod:`clutter_gym.stages.base`). The core builds an env's stages from its settings with :func:`env_stages`."""

from __future__ import annotations

from collections.abc import Sequence

from clutter_gym.noise.action import ActionNoise
from clutter_gym.stages.action_noise import ActionNoiseStage
from clutter_gym.stages.auto_physics import AutoPhysics
from clutter_gym.stages.base import HOOKS, Stage, hooks
from clutter_gym.stages.command import ForwardOnly
from clutter_gym.stages.movables import Movables
from clutter_gym.stages.near_field import NearField
from clutter_gym.stages.render_trail import RenderTrail
from clutter_gym.stages.safety import SafetyMonitor


def env_stages(own: Sequence[Stage], action_noise: ActionNoise, physics: str, near_field: bool,
               render_trail: RenderTrail | None) -> list[Stage]:
    """The stages of an env, in the order their hooks run: ``physics="auto"``; the env module's ``own`` (its
    command mapping, its monitor); the action noise unless clean; movable obstacles (active in a scene that has
    them); the near field when the arena may engage it; the render trail while a render mode is set."""
    stages: list[Stage] = [AutoPhysics()] if physics == "auto" else []
    stages += own
    if not action_noise.is_clean:
        stages.append(ActionNoiseStage(action_noise))
    stages.append(Movables())
    if near_field:
        stages.append(NearField())
    if render_trail is not None:
        stages.append(render_trail)
    return stages


__all__ = ["HOOKS", "ActionNoiseStage", "AutoPhysics", "ForwardOnly", "Movables", "NearField", "RenderTrail",
           "SafetyMonitor", "Stage", "env_stages", "hooks"]
