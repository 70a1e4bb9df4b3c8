"""Checks of the ``gym.make`` keyword arguments every env shares, made before anything is built: each raises naming
the argument and its allowed range (or, for a misspelt keyword, the closest allowed name)."""

from __future__ import annotations

import difflib
import inspect
import math
import os
import sys
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clutter_gym.auto_physics import PHYSICS_MODES
from clutter_gym.datatypes import CollisionReport
from clutter_gym.util.checks import check_integer, is_number

if TYPE_CHECKING:  # core imports this module
    from clutter_gym.core import ClutterEnv

RENDER_MODES = ("human", "rgb_array")
MAX_PHYSICS_HZ = 10000.0  # physics ticks per simulated second, at most
MAX_CONTROL_HZ = 1000.0  # actions per simulated second, at most
#: physics ticks one step may run: a step stays a bounded stretch of simulated and wall time (docs/envs.md,
#: "Physics rate")
MAX_TICKS_PER_STEP = 1000


def check_keywords(cls: type[ClutterEnv], kwargs: Mapping[str, Any]) -> None:
    """Raise a ``TypeError`` naming each keyword the env class ``cls``'s ``__init__`` does not take, with the closest
    allowed name and the list of them."""
    allowed = [name for name, p in inspect.signature(cls.__init__).parameters.items()
               if name != "self" and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    unknown = [name for name in kwargs if name not in allowed]
    if unknown:
        hints = [f"{name!r}{did_you_mean(name, allowed)}" for name in unknown]
        raise TypeError(f"{cls.__name__} got unknown keyword argument(s) {', '.join(hints)}; it takes "
                        f"{sorted(allowed)}")


def did_you_mean(name: Any, allowed: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` with the allowed name closest to ``name``, or "" when none is close."""
    return "".join(f" (did you mean {m!r}?)" for m in difflib.get_close_matches(str(name), allowed, 1))


def check_env_settings(render_mode: str | None, physics_hz: float, control_hz: float, solver_iterations: int,
                       contact_tolerance: float, *, env_id: str, min_physics_hz: float) -> None:
    """Raise at make time, naming the argument, for the settings every env shares (before anything is built);
    ``min_physics_hz`` is the env's floor on the physics rate (``env_id`` names the env in its message)."""
    check_render_mode(render_mode)
    check_rates(physics_hz, control_hz, solver_iterations, env_id=env_id, min_physics_hz=min_physics_hz)
    if not (math.isfinite(contact_tolerance) and 0.0 <= contact_tolerance <= 0.05):
        raise ValueError(f"contact_tolerance must be in [0, 0.05] metres, got {contact_tolerance!r}")


def check_physics_mode(physics: Any) -> None:
    """Raise at make time for a ``physics`` that is not one of :data:`clutter_gym.auto_physics.PHYSICS_MODES`."""
    if not (isinstance(physics, str) and physics in PHYSICS_MODES):
        raise ValueError(f"physics must be one of {PHYSICS_MODES}, got {physics!r}")


def check_numbers(**numbers: Any) -> None:
    """Raise at make time, naming the argument, for a number argument given something else, such as a string or
    None: the range checks after this would fail with Python's or numpy's message, which names no argument. numpy
    scalars are numbers."""
    for name, value in numbers.items():
        if not is_number(value):
            raise ValueError(f"{name} must be a number, got {value!r}")


def check_swept_speed(swept_speed: float) -> None:
    """Raise at make time for a ``swept_speed`` (m/s, above which a link is swept between two checks) that is not
    positive; ``inf`` turns swept checks off."""
    if not (swept_speed > 0.0):
        raise ValueError(f"swept_speed must be > 0 m/s (inf disables swept checks), got {swept_speed!r}")


def check_flags(**flags: Any) -> None:
    """Raise at make time, naming the argument, for a switch that is not a bool: ``"no"`` or ``[1]`` would
    otherwise switch by truthiness."""
    for name, value in flags.items():
        if not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"{name} must be True or False, got {value!r}")


def check_render_mode(render_mode: str | None) -> None:
    """Raise at make time for an unknown mode, or for "human" where no display can show a window."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode must be None or one of {RENDER_MODES}, got {render_mode!r}")
    if render_mode == "human" and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        raise RuntimeError(
            "render_mode='human' opens the pybullet GUI and needs a display (DISPLAY is not set); "
            "use render_mode='rgb_array' on a headless machine"
        )


def check_rates(physics_hz: float, control_hz: float, solver_iterations: int, *, env_id: str = "this env",
                min_physics_hz: float = 1.0) -> None:
    """Raise at make time, naming the argument, for rates or solver settings the control loop cannot run.

    ``min_physics_hz`` is the env's floor: below it the stiffest dynamics it simulates (a rate loop, wheel contact,
    joint motors) break. One step runs ``physics_hz / control_hz`` ticks, at most :data:`MAX_TICKS_PER_STEP`, so a
    step is a bounded stretch of simulated time and of wall time (docs/envs.md, "Physics rate").
    """
    if not (math.isfinite(control_hz) and 0.0 < control_hz <= MAX_CONTROL_HZ):
        raise ValueError(f"control_hz must be in (0, {MAX_CONTROL_HZ:g}] Hz, got {control_hz!r}")
    if not (math.isfinite(physics_hz) and min_physics_hz <= physics_hz <= MAX_PHYSICS_HZ):
        raise ValueError(f"physics_hz must be in [{min_physics_hz:g}, {MAX_PHYSICS_HZ:g}] Hz for {env_id} (below "
                         f"{min_physics_hz:g} Hz its physics is not stable; docs/envs.md, \"Physics rate\"), "
                         f"got {physics_hz!r}")
    if physics_hz < control_hz:
        raise ValueError(f"physics_hz must be in [control_hz={control_hz}, {MAX_PHYSICS_HZ:g}] Hz, got {physics_hz!r}")
    ratio = physics_hz / control_hz
    if ratio > MAX_TICKS_PER_STEP * (1.0 + 1e-9):
        raise ValueError(
            f"control_hz must be at least physics_hz / {MAX_TICKS_PER_STEP} = {physics_hz / MAX_TICKS_PER_STEP:g} Hz "
            f"(a step runs at most {MAX_TICKS_PER_STEP} physics ticks, {MAX_TICKS_PER_STEP / physics_hz:g} s at "
            f"physics_hz={physics_hz:g}), got {control_hz!r}"
        )
    if abs(ratio - round(ratio)) > 1e-9 * ratio:
        raise ValueError(
            f"physics_hz must be an integer multiple of control_hz; {physics_hz} / {control_hz} = {ratio:.6g}"
        )
    check_integer("solver_iterations", solver_iterations, 1, 1000)


def checked_action(action: Any, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``action`` as float64 within ``low``..``high``: any real dtype and container of the right shape, clipped, and
    an object array whose every element is a real number (Python's, numpy's, a Fraction); anything else (strings,
    None, bools, complex numbers, NaN, Inf) is a ``ValueError`` naming the action."""
    shape = low.shape
    try:
        a = np.asarray(action)
    except ValueError:  # ragged nesting
        a = np.empty(0, dtype=object)
    if a.dtype.kind == "O" and a.size and all(is_number(v) for v in a.flat):
        try:
            a = a.astype(np.float64)
        except OverflowError:  # an integer beyond the float range
            raise ValueError(f"action must be finite (no NaN/Inf), got {repr(action)[:200]}") from None
    if a.dtype.kind not in "fiu":
        raise ValueError(f"action must be {shape[0]} real numbers (floats or integers), got {repr(action)[:200]}")
    a = a.astype(np.float64, copy=False)
    if a.shape != shape:
        raise ValueError(f"action must have shape {shape}, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"action must be finite (no NaN/Inf), got {a.tolist()}")
    return np.minimum(np.maximum(a, low), high)


def check_start(report: CollisionReport) -> None:
    """Refuse a user scene that starts in collision: a contact, or self-collision of a pair the ACM checks (at a
    coarse level confirmed with the convex shapes, so the robot's own, not its coarse shapes').

    A generated scene is not checked: its sampler keeps the clutter clear of the start pose, and it starts clear at
    every fidelity level, so it is accepted back as a user scene (tests/test_reach.py checks every level and a padded
    arm: padding is a margin against the world, and self-collision is judged unpadded)."""
    if report.in_contact or report.self_collision is not None:
        what = report.contacts[0] if report.contacts else f"self-collision {report.self_collision}"
        raise ValueError(f"scene starts in collision: {what}")


def check_finite(obs: Mapping[str, np.ndarray]) -> None:
    """Raise ``FloatingPointError`` naming the entries of ``obs`` that hold NaN or Inf."""
    floats = [v for v in obs.values() if v.dtype.kind == "f"]  # integer images cannot hold NaN/Inf
    if not math.isfinite(sum(float(v.sum()) for v in floats)):  # NaN/Inf anywhere poisons the sum
        bad = [key for key, value in obs.items() if not np.all(np.isfinite(value))]
        raise FloatingPointError(f"non-finite observation {bad}: {[obs[k] for k in bad]}")


def not_picklable(env_id: str | None, class_name: str) -> str:
    """Why an env (of id ``env_id``, None when made without gym.make) cannot be pickled or copied, and what to do
    instead."""
    name = f"{env_id} ({class_name})" if env_id else class_name
    return (f"{name} cannot be pickled or copied: it owns a pybullet physics client and FCL collision objects. Make "
            f"a new env instead, with gym.make and the same id and kwargs, and reset it with the same seed; for a "
            f"vector env pass a factory (e.g. lambda: gym.make(...)) rather than an env")
