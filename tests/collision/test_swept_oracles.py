"""The swept audit (``collision/sweep.py``) on the oracle cases physics engines hold their time of impact to
(MuJoCo's engine_toi_test, PhysX's and Unity's documented "flipper"): each with its analytic answer, plus a property
test on random motions against a densely sampled reference. FCL's own ``continuousCollide`` sweeps translation only:
the cases it misses say so."""

from __future__ import annotations

import math

import fcl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from clutter_gym.collision.sweep import CLOSE_ENOUGH, ScrewMotion, time_of_impact
from clutter_gym.datatypes import Obstacle

REACH = 1e-3  # metres: the envs' default contact tolerance
I3 = np.eye(3)


def shape(geometry) -> fcl.CollisionObject:
    return fcl.CollisionObject(geometry, fcl.Transform())


def fixed(geometry, position, rotation=I3) -> fcl.CollisionObject:
    return fcl.CollisionObject(geometry, fcl.Transform(np.asarray(rotation, float), np.asarray(position, float)))


def toi(geometry, radius, pose0, pose1, obstacle, reach=REACH):
    return time_of_impact(shape(geometry), radius, ScrewMotion(*pose0, *pose1), obstacle, reach)


def translation_only_hit(geometry, pose0, pose1, obstacle) -> bool:
    """FCL's continuousCollide with its default request (translation motion, conservative advancement)."""
    moving = fcl.CollisionObject(geometry, fcl.Transform(*pose0))
    result = fcl.ContinuousCollisionResult()
    fcl.continuousCollide(moving, fcl.Transform(*pose1), obstacle, obstacle.getTransform(),
                          fcl.ContinuousCollisionRequest(), result)
    return bool(result.is_collide)


def hinge_pose(angle: float, arm: float) -> tuple[np.ndarray, np.ndarray]:
    """A paddle's pose turned ``angle`` about the z axis through the origin, its centre ``arm`` out along it."""
    rotation = Rotation.from_euler("z", angle).as_matrix()
    return rotation, rotation @ np.array([arm, 0.0, 0.0])


WALL = fcl.Box(0.01, 4.0, 4.0)  # 1 cm thick, at x = 0


def test_a_sphere_at_100_m_per_s_through_a_1_cm_wall():
    """5 m in one 50 ms step: it meets the wall when its surface reaches x = -0.005 - reach."""
    t = toi(fcl.Sphere(0.05), 0.0, (I3, [-2.5, 0, 0]), (I3, [2.5, 0, 0]), fixed(WALL, [0, 0, 0]))
    expected = (2.5 - 0.05 - 0.005 - REACH) / 5.0
    assert t == pytest.approx(expected, abs=2 * CLOSE_ENOUGH / 5.0)


def test_two_spheres_head_on():
    """A sphere of 0.1 m from x = -1 to x = 1 against one of 0.2 m at the origin."""
    t = toi(fcl.Sphere(0.1), 0.0, (I3, [-1, 0, 0]), (I3, [1, 0, 0]), fixed(fcl.Sphere(0.2), [0, 0, 0]))
    assert t == pytest.approx((1.0 - 0.3 - REACH) / 2.0, abs=CLOSE_ENOUGH)


def test_overlapping_at_the_start_is_an_impact_at_time_zero():
    assert toi(fcl.Sphere(0.1), 0.0, (I3, [0.05, 0, 0]), (I3, [1, 0, 0]), fixed(WALL, [0, 0, 0])) == 0.0


def test_separating_and_parallel_motions_meet_nothing():
    away = toi(fcl.Sphere(0.05), 0.0, (I3, [-0.0565, 0, 0]), (I3, [-1.0, 0, 0]), fixed(WALL, [0, 0, 0]))
    box = fcl.Box(0.1, 0.1, 0.1)  # sliding 5 mm from the wall's face
    alongside = toi(box, math.sqrt(3) * 0.05, (I3, [-0.06, -1.0, 0]), (I3, [-0.06, 1.0, 0]), fixed(WALL, [0, 0, 0]))
    assert away is None and alongside is None


@pytest.mark.parametrize("arm", [0.0, 0.25])
def test_a_paddle_that_only_turns_through_a_thin_pole(arm):
    """A 0.5 x 0.02 x 0.05 m paddle turns a quarter turn about the z axis through the origin (about its own
    centre with arm 0, about a hinge at its end with arm 0.25) past a pole of 5 mm radius at 45 degrees, 0.2 m out.
    Both ends of the motion are clear; turning in place, a translation-only sweep sees nothing at all. The paddle's
    face meets the pole when the pole's axis is 1 cm + 5 mm + reach from the paddle's centre line."""
    paddle, pole = fcl.Box(0.5, 0.02, 0.05), fixed(fcl.Cylinder(0.005, 1.0), 0.2 * np.array([1, 1, 0]) / math.sqrt(2))
    radius = math.hypot(0.25, 0.01, 0.025)
    start, end = hinge_pose(0.0, arm), hinge_pose(math.pi / 2, arm)
    t = toi(paddle, radius, start, end, pole)
    turned = math.pi / 4 - math.asin((0.01 + 0.005 + REACH) / 0.2)
    assert t == pytest.approx(turned / (math.pi / 2), abs=1e-4)
    if arm == 0.0:
        assert not translation_only_hit(paddle, start, end, pole)


def test_mixed_translation_and_rotation_against_a_dense_reference():
    """A box turning a quarter turn about z while it crosses 1 m in x and rises 0.2 m, past a thin upright pole that
    stands where the box is half way: the first time within reach, from 20,000 samples of the same screw motion,
    agrees with the advancement's to the samples' spacing."""
    box = fcl.Box(0.3, 0.04, 0.1)
    start = (I3, np.array([-0.5, 0.0, 0.0]))
    end = (Rotation.from_euler("z", math.pi / 2).as_matrix(), np.array([0.5, 0.0, 0.2]))
    motion = ScrewMotion(*start, *end)
    middle = motion.pose(0.5)
    pole = fixed(fcl.Cylinder(0.004, 2.0), middle[1] + middle[0] @ [0.1, 0.0, 0.0])
    radius = math.hypot(0.15, 0.02, 0.05)
    probe = shape(box)

    def distance(s: float) -> float:
        probe.setTransform(fcl.Transform(*motion.pose(s)))
        return fcl.distance(probe, pole, fcl.DistanceRequest(), fcl.DistanceResult())

    assert distance(0.0) > REACH and distance(1.0) > REACH
    ts = np.linspace(0.0, 1.0, 20_001)
    first = next(s for s in ts if distance(s) <= REACH)
    t = time_of_impact(shape(box), radius, motion, pole, REACH)
    assert first - 1 / 20_000 - 1e-9 <= t <= first + 1e-9


def test_a_mesh_through_a_thin_wall():
    """A convex mesh (a box of 12 triangles, as FCL holds a user's mesh) crossing the 1 cm wall in one step."""
    corners = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (-0.05, 0.05)])
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    mesh = fcl.BVHModel()
    mesh.beginModel(len(corners), len(faces))
    mesh.addSubModel(corners, faces)
    mesh.endModel()
    t = toi(mesh, math.sqrt(3) * 0.05, (I3, [-1.0, 0, 0]), (I3, [1.0, 0, 0]), fixed(WALL, [0, 0, 0]))
    assert t == pytest.approx((1.0 - 0.05 - 0.005 - REACH) / 2.0, abs=1e-5)


def test_every_fast_cube_pass_through_a_1_cm_wall_is_flagged():
    """14 cubes of 10 cm at random orientations, 10-20 m/s, over one 50 ms control step across the wall: the
    passes FCL's conservative advancement on boxes missed 3 of."""
    rng = np.random.default_rng(0)
    cube = fcl.Box(0.1, 0.1, 0.1)
    wall = fixed(WALL, [0, 0, 0])
    for _ in range(14):
        rotation = Rotation.random(random_state=rng).as_matrix()
        travel = rng.uniform(10.0, 20.0) / 20.0
        x0 = -0.5 * travel - rng.uniform(-0.01, 0.01)
        start, end = (rotation, np.array([x0, 0.0, 0.0])), (rotation, np.array([x0 + travel, 0.0, 0.0]))
        for pose in (start, end):  # both ends clear: only a sweep can tell
            probe = fixed(cube, pose[1], pose[0])
            assert fcl.distance(probe, wall, fcl.DistanceRequest(), fcl.DistanceResult()) > REACH
        assert toi(cube, math.sqrt(3) * 0.05, start, end, wall) is not None


def test_random_motions_agree_with_a_dense_reference():
    """200 random screw motions of a box (turns up to a half turn, 0.5 m of travel) near a box obstacle. Motions
    whose densely sampled distance dips 2 sample spacings' travel below the reach must be flagged (none missed);
    of those that stay that far above it, at most 5 % may be flagged."""
    rng = np.random.default_rng(1)
    box, radius = fcl.Box(0.2, 0.05, 0.05), math.hypot(0.1, 0.025, 0.025)
    obstacle = fixed(fcl.Box(0.1, 0.3, 0.2), [0, 0, 0])
    missed = flagged_clear = clear = 0
    n = 400
    for _ in range(200):
        start = (Rotation.random(random_state=rng).as_matrix(), rng.uniform(-0.4, 0.4, 3) + [-0.3, 0, 0])
        turn = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * math.pi / math.sqrt(3)).as_matrix()
        end = (start[0] @ turn, start[1] + rng.uniform(-0.5, 0.5, 3) + [0.3, 0, 0])
        motion = ScrewMotion(*start, *end)
        probe = shape(box)
        lowest = math.inf
        for s in np.linspace(0.0, 1.0, n + 1):
            probe.setTransform(fcl.Transform(*motion.pose(s)))
            lowest = min(lowest, fcl.distance(probe, obstacle, fcl.DistanceRequest(), fcl.DistanceResult()))
        margin = 2.0 * motion.travel(radius) / n  # what a motion can dip between two samples, twice over
        hit = time_of_impact(shape(box), radius, motion, obstacle, REACH) is not None
        if lowest <= REACH - margin:
            missed += not hit
        elif lowest > REACH + margin:
            clear += 1
            flagged_clear += hit
    assert missed == 0
    assert clear > 50 and flagged_clear <= 0.05 * clear


@pytest.mark.parametrize("pole_at", ["on the arc", "beyond the hand"])
def test_an_arm_link_that_only_swings_through_a_thin_pole(make_env, pole_at):
    """The Panda's first joint swings 1.2 rad between two checks (the env's checker, the arm's real link poses):
    the hand turns about the base's axis past a 5 mm pole standing where its middle pose puts the hand. Both ends
    are clear; the sweep flags the pass. The same pole 15 cm beyond the hand's reach is not flagged."""
    env = make_env("ClutterReach-v1", robot="panda")
    env.reset(seed=0, options={"scene": {"obstacles": [], "target": [0.4, 0.0, 0.3]}})
    robot, checker = env.unwrapped.robot, env.unwrapped.checker
    ready = np.array(robot.model.ready)

    def state_at(turn: float):
        robot.reset_to(tuple(ready + np.eye(len(ready))[0] * turn))
        return robot.state()

    middle = state_at(0.0)
    hand = middle.links.position[middle.link("panda_hand")]
    out = 0.0 if pole_at == "on the arc" else 0.15
    x, y = hand[:2] * (1.0 + out / np.linalg.norm(hand[:2]))
    checker.set_scene([Obstacle("cylinder", (0.01, 0.01, 1.0), (float(x), float(y)))], [])
    before = checker.check(state_at(-0.6))
    after = checker.check(state_at(0.6))
    assert not before.in_contact and not after.in_contact
    assert (after.tunneling > 0) == (pole_at == "on the arc")
