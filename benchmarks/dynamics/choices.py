"""``dynamics=`` as a choice of the speed-against-error report, one per env: full physics against the reduced model,
the step time of a scripted controller's closed-loop episodes on held-out layouts against the divergence of seeded
open-space runs after 5 s. The three ``*_error`` modules beside this one measure the same at full size."""

from __future__ import annotations

import numpy as np

from benchmarks.choice import Choice, Row
from benchmarks.dynamics import arm_error, flight_error, reduced_error

#: s: the divergence the error column reads
MARK = 5.0


def _rows(closed: dict[str, dict[str, float]], error_mm: float, spread_mm: float) -> list[Row]:
    """The physics row (the default, no error by definition) and the reduced row, with their closed-loop figures."""
    def extra(row: dict[str, float]) -> dict[str, float]:
        return {"success (%)": 100 * row["success"], "collision episodes (%)": 100 * row["collisions"],
                "reduced steps (%)": 100 * row["reduced"]}

    return [Row("physics", closed["physics"]["ms"], 0.0, True, extra(closed["physics"])),
            Row("reduced", closed["reduced"]["ms"], error_mm, False,
                {**extra(closed["reduced"]), "90th pct error (mm)": spread_mm})]


def _why(env: str, closed: dict[str, dict[str, float]], what: str) -> str:
    full, reduced = closed["physics"], closed["reduced"]
    same = (full["success"], full["collisions"]) == (reduced["success"], reduced["collisions"])
    return (f"Full physics stays {env}'s default: the reduced model is a training device, and evaluation runs under "
            f"full physics. It steps {full['ms'] / reduced['ms']:.2f}x faster here ({100 * reduced['reduced']:.0f}% of "
            f"the steps reduced) for {what}; the closed loop's success and collision episodes "
            + ("are the same under both." if same else
               f"move from {full['success']:.0%} / {full['collisions']:.0%} to {reduced['success']:.0%} / "
               f"{reduced['collisions']:.0%}."))


def nav_choice(quick: bool) -> Choice:
    drives, episodes = (3, 5) if quick else (10, 30)
    position, _ = reduced_error.divergence(drives)[MARK]
    closed = {mode: reduced_error.closed_loop(mode, episodes, 0.12) for mode in ("physics", "reduced")}
    error = 1e3 * float(np.median(position))
    return Choice(
        "dynamics-nav", "Dynamics: ClutterNav-v1", "`dynamics`", "env step (ms)", False,
        f"base position gap after {MARK:g} s (mm, median)", _rows(closed, error, 1e3 * np.percentile(position, 90)),
        f"Speed: the env's step time under the potential field, {episodes} held-out layouts at density 0.12 (physics "
        f"then reduced, one after the other). Error: the base's position gap between the models after {MARK:g} s of "
        f"{drives} seeded open-floor drives (random commands held {reduced_error.HOLD:g} s). `python -m "
        "benchmarks.dynamics.reduced_error` measures the same at full size.",
        _why("ClutterNav-v1", closed, f"{error:.0f} mm of the base's path after {MARK:g} s (a fitted unicycle)"))


def fly_choice(quick: bool) -> Choice:
    flights, episodes = (2, 5) if quick else (10, 30)
    position, _ = flight_error.divergence(flights)[MARK]
    closed = {mode: flight_error.closed_loop(mode, episodes, 0.05) for mode in ("physics", "reduced")}
    error = 1e3 * float(np.median(position))
    return Choice(
        "dynamics-fly", "Dynamics: ClutterFly-v1", "`dynamics`", "env step (ms)", False,
        f"position gap after {MARK:g} s (mm, median)", _rows(closed, error, 1e3 * np.percentile(position, 90)),
        f"Speed: the env's step time under the planner reference (the flyer on the subgoal), {episodes} held-out "
        f"layouts at density 0.05 (physics then reduced). Error: the centre of mass's gap between pybullet and the "
        f"model after {MARK:g} s of {flights} seeded free flights (rate commands around the hover held "
        f"{flight_error.HOLD:g} s). `python -m benchmarks.dynamics.flight_error` measures the same at full size, "
        "and with the motors commanded directly.",
        _why("ClutterFly-v1", closed, f"{error:.1e} mm after {MARK:g} s (the same equations as pybullet's)"))


def reach_choice(quick: bool) -> Choice:
    drives, episodes = (2, 5) if quick else (10, 30)
    gaps = arm_error.divergence(drives)[MARK]
    closed = {mode: arm_error.closed_loop("proximity field", mode, episodes) for mode in ("physics", "reduced")}
    error = 1e3 * float(np.median(gaps))
    return Choice(
        "dynamics-reach", "Dynamics: ClutterReach-v1", "`dynamics`", "env step (ms)", False,
        f"hand position gap after {MARK:g} s (mm, median)", _rows(closed, error, 1e3 * np.percentile(gaps, 90)),
        f"Speed: the env's step time under the proximity field, {episodes} held-out layouts (physics then reduced). "
        f"Error: the end effector's gap between pybullet and the model after {MARK:g} s of {drives} seeded drives in "
        f"empty space (joint commands held {arm_error.HOLD:g} s). `python -m benchmarks.dynamics.arm_error` "
        "measures the same at full size, and with the planner reference.",
        _why("ClutterReach-v1", closed, f"{error:.1f} mm of the hand after {MARK:g} s (ideal motors)"))
