"""Tunneling: with pybullet alone a fast ball goes through a thin wall, often without a single contact point; the
FCL audit's swept check flags every such pass, and nothing else would. pybullet's CCD stops the ball only when it
is a rigid body, not a multibody. The nav robot launched into a thin wall ends inside it, and the audit reports it.

Rates and the audit's settings are ClutterNav-v1's defaults; the runs are
:mod:`benchmarks.hard_cases.scenes.tunneling`'s, which ``python -m benchmarks.hard_cases.tunneling`` tabulates.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from benchmarks.hard_cases.scenes.tunneling import GAP, Settings, free_body_run, make_nav_env, nav_run

FAST, THIN = 20.0, 0.01  # m/s, metres
OFFSETS = 8


@pytest.fixture(scope="module")
def nav():
    env = make_nav_env()
    yield env
    env.close()


@pytest.fixture(scope="module")
def settings(nav) -> Settings:
    return Settings.of(nav)


def starts(settings: Settings) -> list[float]:
    """Start offsets spread over one physics tick's travel."""
    return [GAP + k * FAST / settings.physics_hz / OFFSETS for k in range(OFFSETS)]


def ball_runs(settings: Settings, *, rigid: bool = True, ccd: bool = False):
    return [free_body_run(settings, "ball", FAST, THIN, o, rigid=rigid, ccd=ccd) for o in starts(settings)]


@pytest.fixture(scope="module")
def alone(settings):
    return ball_runs(settings)


def test_pybullet_alone_lets_a_fast_ball_through_a_thin_wall_unseen(alone):
    unseen = [r for r in alone if r.outcome == "through" and not r.pybullet_contact]
    assert unseen  # no contact point after any tick: nothing pybullet reports would tell


def test_the_swept_audit_flags_every_pass(alone):
    passes = [r for r in alone if r.passed]
    assert passes and all(r.flagged for r in passes)
    # a pass pybullet never saw ends clear of the wall: only the swept check can flag it
    assert all(r.swept_hits > 0 and not r.fcl_contact for r in passes if not r.pybullet_contact)


def test_the_swept_audit_flags_every_pass_of_a_cube(settings):
    """A 10 cm cube (a multibody, which pybullet's CCD does not stop) through the 1 cm wall at 20 m/s from every
    start offset: each pass is flagged (FCL's translation sweep, the audit before the screw sweep, missed some)."""
    runs = [free_body_run(settings, "cube", FAST, THIN, o, rigid=False, ccd=False) for o in starts(settings)]
    passes = [r for r in runs if r.passed]
    assert passes and all(r.flagged for r in passes)


def test_without_the_swept_check_the_passes_go_unflagged(settings):
    runs = ball_runs(dataclasses.replace(settings, swept_speed=math.inf))
    assert any(r.passed and not r.flagged for r in runs)


def test_pybullet_ccd_stops_the_ball_only_as_a_rigid_body(settings, alone):
    assert not any(r.passed for r in ball_runs(settings, ccd=True))
    multibody = ball_runs(settings, rigid=False)
    assert any(r.passed for r in multibody)
    assert ball_runs(settings, rigid=False, ccd=True) == multibody  # CCD changes nothing on a multibody


def test_the_nav_robot_launched_into_a_thin_wall_is_always_flagged(nav, settings):
    runs = [nav_run(nav, FAST, THIN, o, ccd=False) for o in starts(settings)]
    assert any(r.outcome == "inside" for r in runs)  # pybullet lets the chassis into the wall
    assert all(r.flagged for r in runs)
