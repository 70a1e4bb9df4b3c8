"""Tunneling: fast bodies against thin walls, with pybullet alone, with pybullet's CCD on the fast body, and under
the project's FCL audit; which of them catch a body that goes through or into the wall.

The runs are :mod:`benchmarks.hard_cases.scenes.tunneling`'s, which says how a run ends and what CCD and the audit are.
The table launches a free cube (a multibody and a rigid body) and a free ball at each of ``SPEEDS`` against walls
``WALLS`` thick at ClutterNav-v1's physics rate and checker settings, the ClutterNav-v1 robot at each of ``SPEEDS``
into the same walls, and the ClutterReach-v1 Panda's hand down onto a shelf board and sideways into a shelf side,
each ``BOARDS`` thick. Every case runs the envs' default rates, read from the envs and printed with the table, from
several start offsets spread over one tick's travel (the Panda's boards over ``HAND_SPAN``), and the table counts
runs, each once with pybullet alone and once with its CCD.

    python -m benchmarks.hard_cases.tunneling [--quick]
"""

from __future__ import annotations

import argparse
import time

from benchmarks.hard_cases.scenes.tunneling import (
    EMBEDDED,
    GAP,
    HAND_CASES,
    Run,
    Settings,
    free_body_run,
    hand_run,
    make_nav_env,
    make_reach_env,
    nav_run,
)

SPEEDS = (5.0, 10.0, 20.0)  # launch speeds, m/s
WALLS = (0.01, 0.05)  # wall thicknesses for the launched bodies, metres
BOARDS = (0.01, 0.02)  # the Panda's boards: thin, and as thick as the env's own shelf boards, metres
OFFSETS, QUICK_OFFSETS = 8, 2  # start offsets per case
FREE_BODIES = (("cube", False), ("cube", True), ("ball", True))  # (shape, rigid body rather than multibody)
HAND_SPAN = 0.01  # the Panda's offsets spread over this (more than one tick's travel of its hand), metres


def summary(case: str, speed: str, wall: float, alone: list[Run], with_ccd: list[Run]) -> dict:
    n = len(alone)
    return {
        "case": case, "speed": speed, "wall_cm": 100 * wall, "runs": n,
        "through": sum(r.outcome == "through" for r in alone), "inside": sum(r.outcome == "inside" for r in alone),
        "pybullet_contact": sum(r.pybullet_contact for r in alone),
        "unseen": sum(r.passed and not r.pybullet_contact for r in alone),
        "ccd_through": sum(r.outcome == "through" for r in with_ccd),
        "ccd_inside": sum(r.outcome == "inside" for r in with_ccd),
        "flagged": sum(r.flagged for r in alone),
        "swept_only": sum(r.swept_hits > 0 and not r.fcl_contact for r in alone),
        "passes": sum(r.passed for r in alone),
        "passes_flagged": sum(r.passed and r.flagged for r in alone),
    }


def rows(offsets: int = OFFSETS) -> tuple[list[dict], Settings, Settings]:
    """One summary per case, and the settings of ClutterNav-v1 and ClutterReach-v1."""
    out = []
    nav, reach = make_nav_env(), make_reach_env()
    try:
        nav_settings, reach_settings = Settings.of(nav), Settings.of(reach)
        tick = 1.0 / nav_settings.physics_hz
        for thickness in WALLS:
            for speed in SPEEDS:
                starts = [GAP + k * speed * tick / offsets for k in range(offsets)]
                for shape, rigid in FREE_BODIES:
                    runs = [[free_body_run(nav_settings, shape, speed, thickness, o, rigid=rigid, ccd=ccd)
                             for o in starts] for ccd in (False, True)]
                    name = f"free {shape}, {'rigid body' if rigid else 'multibody'}"
                    out.append(summary(name, f"{speed:g}", thickness, *runs))
                runs = [[nav_run(nav, speed, thickness, o, ccd=ccd) for o in starts] for ccd in (False, True)]
                out.append(summary("nav robot", f"{speed:g}", thickness, *runs))
        for case in HAND_CASES:
            for thickness in BOARDS:
                starts = [k * HAND_SPAN / offsets for k in range(offsets)]
                runs = [[hand_run(reach, case, thickness, o, ccd=ccd) for o in starts] for ccd in (False, True)]
                peak = max(r.peak_speed for r in runs[0])
                out.append(summary(f"Panda hand {case.name}", f"{peak:.1f} (peak)", thickness, *runs))
    finally:
        nav.close()
        reach.close()
    return out, nav_settings, reach_settings


def table(summaries: list[dict]) -> str:
    columns = ("case", "speed (m/s)", "wall", "pybullet: through", "pybullet: inside", "pybullet saw contact",
               "passes pybullet never saw", "CCD: through", "CCD: inside", "audit flagged",
               "by the swept check only", "passes the audit flagged")
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in summaries:
        n = r["runs"]
        counts = [f"{r[key]}/{n}" for key in ("through", "inside", "pybullet_contact", "unseen", "ccd_through",
                                              "ccd_inside", "flagged", "swept_only")]
        lines.append(f"| {r['case']} | {r['speed']} | {r['wall_cm']:g} cm | " + " | ".join(counts)
                     + f" | {r['passes_flagged']}/{r['passes']} |")
    return "\n".join(lines)


def main() -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_OFFSETS} start offsets per case, not {OFFSETS}")
    offsets = QUICK_OFFSETS if parser.parse_args().quick else OFFSETS
    t0 = time.perf_counter()
    summaries, nav, reach = rows(offsets)
    print(f"ClutterNav-v1 (and the free bodies): {nav.describe()}")
    print(f"ClutterReach-v1: {reach.describe()}")
    print(f"{offsets} start offsets per case; inside = deeper than {1000 * EMBEDDED:.0f} mm into the wall at the end\n")
    print(table(summaries))
    print(f"\n{time.perf_counter() - t0:.1f} s")
    return summaries


if __name__ == "__main__":
    main()
