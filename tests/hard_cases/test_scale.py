"""Scale and translation: the same scene at the origin and translated by (1e3, 1e3, 0) and (1e4, 1e4, 0) m, built
from the env's own parts (Sim, obstacle pool, FCL checker, LIDAR); millimetre obstacles; the largest arena.

The envs have no world-offset option, so the translated scenes are built by construction
(:mod:`benchmarks.hard_cases.scenes.scale`, which ``benchmarks.hard_cases.catalogue`` shares): every obstacle, the arena
walls and the robot pose move by the offset (the floor is an infinite plane). Measured on 200 seeded robot poses in
a 6 m arena (plus three hand-placed ones: 5 mm into a box, touching a box face, clear), translated minus
untranslated, metres (np.spacing: 1.1e-13 at 1e3, 1.8e-12 at 1e4):

* FCL, sphere shapes (closed-form routines): distance <= 3.2e-13 at 1e3 and 2.7e-12 at 1e4 (2.8 and 1.5 ulp), witness
  points <= 3.1e-12, the same nearest obstacle -> ``EXACT_ULPS`` = 20 ulp of the offset (1.8e-11 at 1e4).
* FCL, cylinder shapes (chassis, wheels; libccd GJK, no closed form in FCL 0.7): the chassis against its closed
  form has a median error of 1.4e-9 to 5.1e-9 at every offset, but a long tail: 2.4e-4 for one pose at 1e3, while
  the worst at the origin and at 1e4 is 2.2e-6 (GJK stalls, at other poses for another offset), never below the
  closed form. Translation does not widen the tail: ``GJK_TOL`` = 1e-3 (4x the worst; the bound of
  tests/collision/test_fcl_analytic.py).
* FCL contact depths (EPA): <= 4.8e-7 -> ``EPA_TOL`` = 1e-5.
* pybullet contacts: the same (body, link, link) pairs with the same number of points; the deepest point of each
  pair within 8.8e-14 at 1e3 and 2.2e-12 at 1e4 (1.2 ulp) -> ``CONTACT_ULPS`` = 20. Contact positions and normals
  are not compared: a face lying on a face has no unique contact point, and Bullet's manifold picks different ones
  (1.3 cm apart at 1e3).
* LIDAR ranges (``rayTestBatch``, double precision): <= 1.1e-11 at 1e3 and 1.4e-10 at 1e4 (95 and 78 ulp) ->
  ``RAY_ULPS`` = 500 (9e-10 at 1e4).
* 2 s of full command into a box (240 physics ticks): base pose within 5.9e-13 at 1e3 and 8.5e-12 at 1e4 (5 ulp)
  -> ``POSE_ULPS`` = 20; the same contact flags on every step.

One real limit, not of FCL or Bullet's double-precision core: pybullet reports ``worldLinkFramePosition`` (the URDF
link frame, which ``Sim.link_states`` and ``Sim.link_frame`` read) rounded to float32, because it composes the
centre-of-mass pose with the inertial offset in Bullet3's single-precision ``b3Transform``. The link frames are off
by up to half a float32 ulp of the coordinate: 1.2e-7 m at 2 m, 3e-5 m at 1e3, 4.9e-4 m at 1e4, and FCL clearances
of every link but the base with them (a caster 0.12 mm off at 1e4). Inside the largest arena (|x| <= 15 m) that is
at most 1e-6 m. The centre-of-mass pose (``linkWorldPosition``) is double, and ``Sim.link_states`` builds the link
frames from it (``test_link_states_keep_double_precision``), and so does ``Sim.link_frame`` (a camera's mount, the
Panda's IK target; ``test_link_frame_keeps_double_precision``), which read the float32 frame before.

Millimetre obstacles (a 2 mm rod, a 1 mm cube on the floor and one at chassis height; 10 mm and 2 mm clear,
touching, 0.3 mm deep; at the origin and at 1e4 m): FCL within 5.0e-6 of the closed forms (the exact touch of the
caster with the cube's edge, through the signed request's GJK; 4.2e-9 for the rod, 7.7e-7 for the raised cube) ->
``MM_TOL`` = 2e-5; pybullet's deepest contact within 4.2e-5 of them (the caster on the cube; 1.6e-5 the rod) ->
``MM_CONTACT_TOL`` = 1e-4; the LIDAR's forward beam meets the rod's 64-gon prism at its corner, 0.8 um outside the
circle, exactly (4e-13). The largest arena (30 m, LIDAR range 100 m): every wall range and the clearance against
closed forms (ranges within 4.0e-12 m, 1e-10 allowed; clearance 2.9e-8 m, GJK, 1e-6 allowed).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from helpers import CHASSIS_RADIUS, empty_scene

from benchmarks.hard_cases.scenes.scale import (
    CASTER_RADIUS,
    CONTACT_ULPS,
    EPA_TOL,
    EXACT_ULPS,
    GJK_TOL,
    HAND_POSES,
    LIDAR_X,
    MM_CONTACT_TOL,
    MM_TOL,
    OFFSETS,
    POSE_ULPS,
    POSES,
    PRISM_CORNER,
    RAY_ULPS,
    ROD,
    build,
    drive_into_box,
    measure,
    millimetre_errors,
    millimetre_pairs,
    millimetre_scene,
    read_placed,
    ulps,
)
from clutter_gym.robots.diffdrive import TRACKED_LINKS
from clutter_gym.sensors.lidar import Lidar, LidarConfig
from clutter_gym.sim import Sim, pb
from clutter_gym.urdf.kinematics import UrdfKinematics


@pytest.fixture(scope="module")
def worlds():
    made = {offset: build(offset) for offset in (0.0, *OFFSETS)}
    yield made
    for world in made.values():
        world.sim.close()


@pytest.mark.parametrize("offset", OFFSETS)
def test_fcl_clearance_matches_the_untranslated_scene(worlds, offset):
    origin, far = worlds[0.0], worlds[offset]
    kinds = np.array([s.kind for s in origin.checker.model.shapes])
    spheres, cylinders = kinds == "sphere", kinds == "cylinder"
    assert spheres.sum() == 2 and cylinders.sum() == 3  # casters; chassis and wheels
    for pose in POSES:
        d0, other0, points0, contacts0 = measure(origin, pose)
        d1, other1, points1, contacts1 = measure(far, pose)
        assert (other1 == other0).all(), pose
        np.testing.assert_allclose(d1[spheres], d0[spheres], rtol=0, atol=ulps(offset, EXACT_ULPS), err_msg=str(pose))
        apart = spheres & (d0 > 0)  # witness points are unique between separated convex shapes
        np.testing.assert_allclose(points1[apart], points0[apart], rtol=0, atol=ulps(offset, EXACT_ULPS))
        np.testing.assert_allclose(d1[cylinders], d0[cylinders], rtol=0, atol=GJK_TOL, err_msg=str(pose))
        assert [c[:2] for c in contacts1] == [c[:2] for c in contacts0], pose
        np.testing.assert_allclose([c[2] for c in contacts1], [c[2] for c in contacts0], rtol=0, atol=EPA_TOL)


@pytest.mark.parametrize("offset", (0.0, *OFFSETS))
def test_fcl_clearance_against_closed_forms(worlds, offset):
    """Separated casters: the sphere's closed form (exact); the chassis, an upright cylinder overlapping every
    obstacle's height: its footprint distance (GJK: above it by at most ``GJK_TOL``, never below)."""
    world = worlds[offset]
    model = world.checker.model
    casters = [i for i, s in enumerate(model.shapes) if s.kind == "sphere"]
    chassis = [s.link for s in model.shapes].index("base_link")
    tol = max(ulps(offset, EXACT_ULPS), 1e-12)
    errors = []
    for pose in POSES:
        distance, _, _, _ = measure(world, pose)
        for i in casters:
            exact = min(o.distance3d(model.position[i]) for o in world.obstacles) - CASTER_RADIUS
            if exact > 0.0:
                assert distance[i] == pytest.approx(exact, abs=tol), pose
        centre = model.position[chassis]
        footprint = min(float(o.distance(np.array(centre[0]), np.array(centre[1]))) for o in world.obstacles)
        if footprint > CHASSIS_RADIUS:
            errors.append(distance[chassis] - (footprint - CHASSIS_RADIUS))
    errors = np.array(errors)
    assert len(errors) > 150
    assert errors.min() >= -tol and errors.max() <= GJK_TOL
    assert np.median(np.abs(errors)) < 1e-7  # the tail is rare at every offset: measured 1.4e-9 to 5.1e-9


@pytest.mark.parametrize("offset", OFFSETS)
def test_contacts_and_lidar_match_the_untranslated_scene(worlds, offset):
    """pybullet's contact points (and the checker's contact flags) and the LIDAR, robot placed through pybullet."""
    origin, far = worlds[0.0], worlds[offset]
    lidar = Lidar(LidarConfig(n_rays=360, max_range=10.0))
    touching = 0
    for pose in POSES:
        (c0, ranges0, report0), (c1, ranges1, report1) = (read_placed(world, pose, lidar) for world in (origin, far))
        assert c1.keys() == c0.keys(), pose
        for key, (n, deepest) in c0.items():
            assert c1[key][0] == n, (pose, key)
            assert c1[key][1] == pytest.approx(deepest, abs=ulps(offset, CONTACT_ULPS)), (pose, key)
        assert (report1.pybullet_contacts, report1.n_contacts, report1.disagreement) == \
            (report0.pybullet_contacts, report0.n_contacts, report0.disagreement), pose
        touching += report0.pybullet_contacts > 0
        np.testing.assert_allclose(ranges1, ranges0, rtol=0, atol=ulps(offset, RAY_ULPS), err_msg=str(pose))
        assert ((ranges1 < 10.0) == (ranges0 < 10.0)).all()
    assert touching >= 10  # the poses do reach into obstacles


@pytest.mark.parametrize("offset", OFFSETS)
def test_driving_into_a_box_matches_the_untranslated_scene(worlds, offset):
    """2 s of full command (with a slight turn) from 0.33 m in front of a box: the same trajectory and contacts."""
    runs = [drive_into_box(world) for world in (worlds[0.0], worlds[offset])]
    assert sum(step[2] > 0 for step in runs[0]) > 10  # it reached the box and pressed on
    for (p0, yaw0, pb0, n0), (p1, yaw1, pb1, n1) in zip(*runs):
        np.testing.assert_allclose(p1, p0, rtol=0, atol=ulps(offset, POSE_ULPS))
        assert yaw1 == pytest.approx(yaw0, abs=ulps(offset, POSE_ULPS))
        assert (pb1, n1) == (pb0, n0)


def test_pybullet_reports_link_frames_in_float32_and_centres_of_mass_in_float64(worlds):
    """The limit behind the xfail below: pybullet's ``worldLinkFramePosition`` is the float32 rounding of the exact
    frame, its ``linkWorldPosition`` (the centre of mass) is exact."""
    world = worlds[1e4]
    world.place(2.0, -2.0, 0.0)
    link = world.robot.link_index["front_caster"]
    row = pb.getLinkState(world.robot.body, link, computeForwardKinematics=1, physicsClientId=world.sim.client_id)
    exact = world.exact_state(2.0, -2.0, 0.0).links.position[TRACKED_LINKS.index("front_caster")]
    np.testing.assert_allclose(row[0], exact, rtol=0, atol=ulps(1e4, 4))  # the caster's inertial origin is its frame
    np.testing.assert_array_equal(row[4], exact.astype(np.float32))
    assert np.abs(np.subtract(row[4], exact)).max() > 1e-4


@pytest.mark.parametrize("offset", OFFSETS)
def test_link_states_keep_double_precision(worlds, offset):
    """The robot's link frames as ``Sim.link_states`` reads them, and the FCL clearance of every shape through
    ``robot.state()``, equal those of the exact poses far from the origin."""
    world = worlds[offset]
    for pose in HAND_POSES:
        world.place(*pose)
        state, exact = world.robot.state(), world.exact_state(*pose)
        np.testing.assert_allclose(state.links.position, exact.links.position, rtol=0, atol=ulps(offset, POSE_ULPS))
        np.testing.assert_allclose(state.links.rotation, exact.links.rotation, rtol=0, atol=1e-12)
        world.checker.sync(state)
        through_pybullet = world.checker.clearance()[0]
        world.checker.sync(exact)
        np.testing.assert_allclose(through_pybullet, world.checker.clearance()[0], rtol=0, atol=ulps(offset, 20))


@pytest.mark.parametrize("offset", OFFSETS)
def test_link_frame_keeps_double_precision(worlds, offset):
    """``Sim.link_frame`` (a camera's mount, the Panda's IK target) builds the frame from the double-precision centre
    of mass as ``Sim.link_states`` does: every tracked link's frame equals the exact one far from the origin (it
    read pybullet's float32 frame, up to 4.9e-4 m off at 1e4 m)."""
    world = worlds[offset]
    for pose in HAND_POSES:
        world.place(*pose)
        exact = world.exact_state(*pose)
        for row, name in enumerate(TRACKED_LINKS):
            origin, rotation = world.sim.link_frame(world.robot.body, world.robot.link_index[name])
            np.testing.assert_allclose(origin, exact.links.position[row], rtol=0, atol=ulps(offset, POSE_ULPS),
                                       err_msg=f"{name} at {pose}")
            np.testing.assert_allclose(rotation, exact.links.rotation[row], rtol=0, atol=1e-12, err_msg=name)


TURNED_INERTIA_URDF = """<robot name="turned"><link name="base"><inertial><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="arm"><inertial><origin xyz="0.05 -0.02 0.03" rpy="0.4 -0.3 0.7"/><mass value="0.5"/>
<inertia ixx="0.002" iyy="0.003" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.1 0.05 0.05"/></geometry></collision></link>
<joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
<origin xyz="0.3 0.1 0.2" rpy="0.3 0.2 0.1"/>
<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint></robot>
"""


@pytest.mark.parametrize("offset", (0.0, 1e4))
def test_link_frame_of_a_link_whose_inertial_frame_is_turned(tmp_path, offset):
    """A link whose centre of mass is offset and turned in its frame (the diffbot's are not): ``Sim.link_frame`` equals
    the URDF's forward kinematics, at 1e4 m too."""
    urdf = tmp_path / "turned.urdf"
    urdf.write_text(TURNED_INERTIA_URDF)
    sim = Sim()
    try:
        body = sim.load_urdf("turned", urdf, position=(offset, offset, 1.0), fixed_base=True)
        sim.actuation.reset_joints(body, [0], [0.5])
        origin, rotation = sim.link_frame(body, 0)
        exact = UrdfKinematics(urdf).forward(np.array([[0.5]]))["arm"][0]
        np.testing.assert_allclose(origin, exact[:3, 3] + [offset, offset, 1.0], rtol=0, atol=ulps(1.0 + offset, 20))
        np.testing.assert_allclose(rotation, exact[:3, :3], rtol=0, atol=1e-12)
    finally:
        sim.close()


# ------------------------------------------------------------------------------------------ millimetre obstacles


@pytest.mark.parametrize("offset", (0.0, 1e4))
@pytest.mark.parametrize("gap", [0.01, 0.002, 0.0, -0.0003])
def test_millimetre_obstacles(offset, gap):
    """FCL and pybullet's contacts against the closed forms, the LIDAR's forward beam against the rod (with either
    ray caster); at 1e4 m too. The closed form of each obstacle's distance to its robot shape is ``gap`` by
    construction."""
    world = build(offset, millimetre_scene(gap))
    try:
        world.place(0.0, 0.0, 0.0)
        state = world.exact_state(0.0, 0.0, 0.0)
        report = world.checker.check(state, world.sim.contact_distances(world.robot.body))
        caster = world.checker.model.position[millimetre_pairs(world)[1][0]]
        assert world.obstacles[1].distance3d(caster) - CASTER_RADIUS == pytest.approx(gap, abs=ulps(1.0 + offset, 20))
        fcl_errors, contact_errors = millimetre_errors(world, gap)
        assert np.abs(fcl_errors).max() <= MM_TOL, fcl_errors
        assert report.min_clearance == pytest.approx(gap, abs=MM_TOL)
        if gap > 0:
            assert report.n_contacts == report.pybullet_contacts == 0
            for caster, rod_face in (("exact", ROD), ("pybullet", PRISM_CORNER)):
                # azimuth 0 (a full circle starts at -pi) meets the rod's circle, or a corner of pybullet's prism
                lidar = Lidar(LidarConfig(n_rays=720, max_range=3.5, caster=caster))
                ranges = lidar.read_clean(world.sim, world.robot.state())
                assert ranges[360] == pytest.approx(CHASSIS_RADIUS + gap + ROD - rod_face - LIDAR_X, abs=1e-9)
                assert (np.delete(ranges, 360) == 3.5).all()  # the rod is too thin for the next beams; nothing else
        else:  # every engine sees all three obstacles touch or overlap the robot
            assert not report.disagreement
            assert sorted((c.link, c.obstacle) for c in report.contacts) == \
                [("base_link", 0), ("base_link", 2), ("front_caster", 1)]
            assert np.abs(contact_errors).max() <= MM_CONTACT_TOL, contact_errors
    finally:
        world.sim.close()


# ---------------------------------------------------------------------------------------------- the largest arena
def test_the_largest_arena_measures_its_walls_exactly():
    """arena_size 30 (the maximum; tests/hard_cases/test_settings.py fills it with clutter), LIDAR range 100 m (the
    maximum): from a corner every beam reaches a wall (42 m away at most) at the closed-form range, the clearance
    is the distance to the nearer wall less the chassis radius; after a few steps the readings stay finite."""
    half, n = 15.0, 360
    start = (13.0, -14.0, 2.5)
    env = gym.make("ClutterNav-v1", arena_size=30.0, lidar_range=100.0, n_rays=n, noise="none")
    try:
        obs, info = env.reset(options={"scene": empty_scene(start=start, goal=(-14.0, 14.0))})
        x, y, yaw = start
        origin = np.array([x + LIDAR_X * math.cos(yaw), y + LIDAR_X * math.sin(yaw)])
        angles = yaw + LidarConfig(n_rays=n).angles
        direction = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        with np.errstate(divide="ignore"):  # the nearest wall face ahead of each beam
            t = np.where(direction != 0, np.where(direction > 0, half - origin, -half - origin) / direction, np.inf)
        np.testing.assert_allclose(info["lidar_ranges"], t.min(axis=1), rtol=0, atol=1e-10)
        assert info["lidar_ranges"].max() > 40.0
        assert info["min_clearance"] == pytest.approx(min(half - abs(x), half - abs(y)) - CHASSIS_RADIUS, abs=1e-6)
        np.testing.assert_allclose(obs["lidar"], info["lidar_ranges"] / 100.0, rtol=1e-6)
        for _ in range(5):
            obs, reward, _, _, info = env.step(np.array([1.0, 0.5], dtype=np.float32))
            assert all(np.all(np.isfinite(v)) for v in obs.values()) and np.isfinite(reward)
            assert np.isfinite(info["min_clearance"]) and (obs["lidar"] < 1.0).all()
    finally:
        env.close()


def test_the_largest_arena_seen_by_a_short_lidar_reads_its_maximum_range():
    env = gym.make("ClutterNav-v1", arena_size=30.0, noise="none")  # lidar_range 3.5 m, walls 15 m away
    try:
        obs, info = env.reset(options={"scene": empty_scene(goal=(10.0, 10.0))})
        assert (info["lidar_ranges"] == 3.5).all() and (obs["lidar"] == 1.0).all()
        assert info["min_clearance"] == pytest.approx(15.0 - CHASSIS_RADIUS, abs=1e-6)
    finally:
        env.close()
