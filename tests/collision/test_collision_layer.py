"""The collision layer on the Panda: URDF geometry and kinematics, fidelity levels, the ACM, self-collision,
contacts with depth, witness points and swept checks, against analytic answers and pybullet."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks.hard_cases.scenes.penetration_depth import panda_depth_errors
from clutter_gym.collision import (
    FIDELITY_LEVELS,
    CollisionChecker,
    RobotCollisionModel,
    UrdfKinematics,
    build_link_shapes,
    generate_acm,
    load_acm,
    load_collision_elements,
)
from clutter_gym.collision import acm as acm_module
from clutter_gym.collision.fidelity import fitted_primitive
from clutter_gym.datatypes import LinkStates, Obstacle, RobotState
from clutter_gym.robots import DiffDriveRobot, PandaArm
from clutter_gym.robots.panda import READY

URDF = PandaArm().urdf_path
KIN = UrdfKinematics(URDF)
FINGERS = [0.02, 0.02]


def synced(model: RobotCollisionModel, q) -> RobotCollisionModel:
    frames = KIN.forward(np.concatenate([q, FINGERS])[None])
    model.sync(np.stack([frames[n][0, :3, 3] for n in KIN.links]), np.stack([frames[n][0, :3, :3] for n in KIN.links]))
    return model


# ------------------------------------------------------------------------------------------ geometry, FK
def test_forward_kinematics_matches_pybullet_link_frames(make_env):
    env = make_env("ClutterReach-v1").unwrapped
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(5):
        env.step(rng.uniform(-1, 1, 7))
        state = env.robot.state()
        frames = KIN.forward(np.concatenate([state.joint_position, FINGERS])[None])
        for row, name in enumerate(state.link_names):
            # the fingers' motors hold 0.02 m to within 3e-5 m, which moves the finger frames by as much
            tol = 1e-4 if "finger" in name else 1e-6
            np.testing.assert_allclose(frames[name][0, :3, 3], state.links.position[row], atol=tol)
            np.testing.assert_allclose(frames[name][0, :3, :3], state.links.rotation[row], atol=1e-6)


def test_every_panda_link_loads_its_obj_mesh():
    elements = load_collision_elements(URDF)
    assert [e.link for e in elements] == [f"panda_link{i}" for i in range(8)] + ["panda_hand", "panda_leftfinger",
                                                                                   "panda_rightfinger"]
    assert all(e.kind == "mesh" and len(e.mesh.faces) >= 32 for e in elements)


def test_bad_urdfs_raise_naming_the_link(tmp_path):
    missing = tmp_path / "a.urdf"
    missing.write_text('<robot name="r"><link name="l"><collision><geometry><mesh filename="nope.obj"/></geometry>'
                       "</collision></link></robot>")
    with pytest.raises(ValueError, match="link 'l'.*nope.obj|nope.obj"):
        load_collision_elements(missing)
    cone = tmp_path / "b.urdf"
    cone.write_text('<robot name="r"><link name="k"><collision><geometry><cone radius="1"/></geometry></collision>'
                    "</link></robot>")
    with pytest.raises(ValueError, match="link 'k'.*<cone> collision geometry is not supported"):
        load_collision_elements(cone)
    with pytest.raises(ValueError, match="URDF not found"):
        load_collision_elements(tmp_path / "absent.urdf")


def test_fitted_primitive_encloses_the_points():
    points = np.random.default_rng(1).normal(size=(400, 3)) * [0.3, 0.05, 0.04]
    kind, size, position, rotation = fitted_primitive(points)
    local = (points - position) @ rotation
    if kind == "box":
        assert np.all(np.abs(local) <= 0.5 * np.array(size) + 1e-9)
    else:
        radius, length = size
        axial = np.clip(local[:, 2], -length / 2, length / 2)
        gap = np.linalg.norm(local - np.c_[np.zeros_like(axial), np.zeros_like(axial), axial], axis=1)
        assert kind == "capsule" and np.all(gap <= radius + 1e-9)


@pytest.mark.parametrize("fidelity", ["sphere", "primitive", "convex"])
def test_coarser_levels_never_report_more_clearance_than_the_mesh(fidelity):
    """Every approximation encloses the mesh, so near an obstacle its clearance is never larger (up to GJK's
    error on the hulls, under 1e-4 m within 0.15 m; it grows with distance: 2.5e-4 m at 0.23 m)."""
    box = Obstacle("box", (0.3, 0.3, 0.3), (0.45, 0.1), 0.3, 0.0)
    checkers = []
    for level in (fidelity, "mesh"):
        model = RobotCollisionModel.from_urdf(URDF, level, KIN.links, self_collision=False)
        checkers.append(CollisionChecker(model, "panda_link0", clearance_range=2.0, fixed_links=("panda_link0",)))
        checkers[-1].set_scene([box], [])
    rng = np.random.default_rng(2)
    checked = 0
    for _ in range(300):
        q = rng.uniform(KIN.lower[:7], KIN.upper[:7])
        coarse, fine = (synced(c.model, q) and c.clearance()[0].min() for c in checkers)
        if 0.0 < fine < 0.15:
            assert coarse <= fine + 1e-4
            checked += 1
    assert checked > 20


# ----------------------------------------------------------------------------------------------- ACM
@pytest.fixture(scope="module")
def sampled_acm():
    return generate_acm(URDF, "convex", samples=1500, seed=3)


def test_acm_rules(sampled_acm):
    acm = sampled_acm
    adjacent = {p for p, reason in acm.disabled.items() if reason == "adjacent"}
    chain = [f"panda_link{i}" for i in range(8)] + ["panda_hand"]
    expected = {tuple(sorted(p)) for p in zip(chain, chain[1:])}  # link7-hand through the geometry-less link8
    expected |= {tuple(sorted(("panda_hand", f))) for f in ("panda_leftfinger", "panda_rightfinger")}
    assert adjacent == expected
    for pair, fraction in acm.fraction.items():
        reason = acm.disabled.get(pair)
        if 0.0 < fraction < acm_module.ALWAYS_FRACTION:
            assert reason is None, f"{pair} collides in {fraction:.1%} of samples but is disabled ({reason})"
        elif fraction == 0.0:
            assert reason == "never"
        else:
            assert reason == "always"
    assert ("panda_link1", "panda_link6") in acm.enabled  # collides in some folded poses (below)


def test_acm_is_cached_by_urdf_content_and_fidelity(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(acm_module, "SHIPPED_DIR", tmp_path / "none")
    first = load_acm(URDF, "sphere", samples=200)
    files = list((tmp_path / "clutter-gym" / "acm").glob("*.json"))
    assert len(files) == 1 and json.loads(files[0].read_text())["key"] == first.key

    def refuse(*_args, **_kwargs):
        raise AssertionError("regenerated although cached")

    monkeypatch.setattr(acm_module, "generate_acm", refuse)
    assert load_acm(URDF, "sphere", samples=200).enabled == first.enabled
    changed = tmp_path / "panda.urdf"  # same robot, different text: a different key
    changed.write_text(URDF.read_text().replace("package://meshes", str(URDF.parent / "meshes")) + "\n")
    assert acm_module.acm_key(changed, "sphere", 200, 0) != first.key


@pytest.mark.parametrize("fidelity", FIDELITY_LEVELS)
def test_shipped_acms_match_the_current_urdfs(fidelity, monkeypatch):
    """The committed ACMs are found by key, so editing a URDF or the rules makes them regenerate."""
    monkeypatch.setattr(acm_module, "generate_acm", lambda *a, **k: pytest.fail("shipped ACM missing or stale"))
    for urdf in (URDF, DiffDriveRobot().urdf_path):
        load_acm(urdf, fidelity)


# -------------------------------------------------------------------------------------- self-collision
KNOWN = [
    ("ready", READY, None),
    ("elbow folded, wrist down", (0.0, 0.3, 0.0, -3.07, 0.0, 0.0, 0.785), ("panda_link1", "panda_link6")),
    ("hand into the base", (0.0, 1.7, 0.0, -3.0, 0.0, 3.7, 0.0), ("panda_link0", "panda_link6")),
]


@pytest.mark.parametrize("fidelity", ["convex", "mesh"])
@pytest.mark.parametrize(("name", "q", "pair"), KNOWN, ids=[k[0] for k in KNOWN])
def test_known_panda_configurations(fidelity, name, q, pair):
    """pybullet (its own GJK on the same hulls) measures these pairs at -2.7 cm and -11.7 cm, ready at +2.0 cm."""
    model = synced(RobotCollisionModel.from_urdf(URDF, fidelity, KIN.links), np.array(q))
    clearance = model.self_clearance()
    if pair is None:
        assert model.self_collision() is None and clearance.distance > 0.015
    else:
        assert model.self_collision() is not None
        assert clearance.links == pair and clearance.distance < -0.02


# --------------------------------------------------------------------------- contacts, witnesses, sweeps
def ball_checker(radius: float = 0.05, **kwargs) -> CollisionChecker:
    """A checker for a robot that is one ball on link "ball" (pose row 1; row 0 is the base)."""
    shape = build_link_shapes(load_collision_elements(_ball_urdf(radius)), "primitive")
    model = RobotCollisionModel(shape, ("base", "ball"))
    return CollisionChecker(model, "base", fixed_links=("base",), **kwargs)


def _ball_urdf(radius: float):
    import tempfile
    from pathlib import Path

    path = Path(tempfile.mkdtemp()) / "ball.urdf"
    path.write_text(f'<robot name="b"><link name="base"/><link name="ball"><collision><geometry>'
                    f'<sphere radius="{radius}"/></geometry></collision></link><joint name="j" type="floating">'
                    '<parent link="base"/><child link="ball"/></joint></robot>')
    return path


def ball_state(x: float, y: float = 0.0, z: float = 0.5) -> RobotState:
    links = LinkStates(np.array([[x, y, z]]), np.eye(3)[None], np.zeros((1, 3)), np.zeros((1, 3)))
    return RobotState(np.zeros(3), np.eye(3), (0, 0, 0), (0, 0, 0), links, ("ball",), {}, -1)


WALL = Obstacle("box", (0.01, 1.0, 1.0), (0.0, 0.0))  # 1 cm thick, x in [-0.005, 0.005], z in [0, 1]


def test_contact_depth_and_witness_points():
    checker = ball_checker(0.05)
    checker.set_scene([WALL], [])
    report = checker.check(ball_state(-0.035))  # ball surface 2 cm into the wall
    assert report.contacts[0].depth == pytest.approx(0.02, abs=1e-6)
    assert report.min_clearance == pytest.approx(-0.02, abs=1e-6)
    report = checker.check(ball_state(-0.155, 0.1, 0.4))  # 10 cm clear
    assert report.min_clearance == pytest.approx(0.1, abs=1e-6) and not report.contacts
    np.testing.assert_allclose(report.witness, [[-0.105, 0.1, 0.4], [-0.005, 0.1, 0.4]], atol=1e-6)
    np.testing.assert_allclose(report.directions[0], [1.0, 0.0, 0.0], atol=1e-6)


def test_contact_depth_is_the_padded_signed_distance():
    """Padding inflates the ball: 2 cm into the wall plus 1 cm of padding is 3 cm deep, as the clearance says."""
    checker = ball_checker(0.05)
    checker.model.padding[:] = 0.01
    checker.set_scene([WALL], [])
    report = checker.check(ball_state(-0.035))
    assert report.contacts[0].depth == pytest.approx(0.03, abs=1e-6)
    assert report.min_clearance == pytest.approx(-0.03, abs=1e-6)


def test_panda_contact_depths_agree_with_the_signed_distance():
    """fcl.collide's depth on a hull ran up to 2.3x the signed distance's on these steps (full joint speed into
    clutter); the reported depth is the signed distance's."""
    worst, _, deep, _ = panda_depth_errors(800, seed=0)
    assert worst < 1e-9
    assert deep > 0


def test_a_ball_through_a_thin_wall_is_caught_by_the_swept_check_only():
    checker = ball_checker(0.05, swept_speed=0.2, dt=0.05)
    checker.set_scene([WALL], [])
    before = checker.check(ball_state(-0.2))
    after = checker.check(ball_state(0.2))  # 0.4 m in one 50 ms step: both ends clear of the wall
    assert not before.in_contact and not after.in_contact and after.min_clearance > 0.1
    assert after.tunneling == 1
    checker.check(ball_state(-0.2, y=0.9))
    assert checker.check(ball_state(0.2, y=0.9)).tunneling == 0  # passes beside the wall
    checker.check(ball_state(-0.2))
    slow = ball_checker(0.05, swept_speed=10.0, dt=0.05)  # below the speed threshold: not swept
    slow.set_scene([WALL], [])
    slow.check(ball_state(-0.2))
    assert slow.check(ball_state(0.2)).tunneling == 0


def test_a_ball_leaving_a_contact_fast_is_no_tunneling():
    """The sweep of a ball that starts against the wall hits it at time 0; leaving a contact is not passing through.
    Starting 1 cm clear instead, the same step through the wall is flagged."""
    checker = ball_checker(0.05, swept_speed=0.2, dt=0.05)
    checker.set_scene([WALL], [])
    assert checker.check(ball_state(-0.0549)).in_contact  # 0.1 mm into the wall
    after = checker.check(ball_state(-0.4))  # 0.35 m away in one 50 ms step
    assert not after.in_contact and after.tunneling == 0
    checker.check(ball_state(-0.065))
    assert checker.check(ball_state(0.3)).tunneling == 1


def test_padding_is_an_exact_inflation():
    checker = ball_checker(0.05)
    padded = CollisionChecker(RobotCollisionModel(checker.model.shapes, ("base", "ball"), padding=0.03), "base",
                              fixed_links=("base",))
    for c in (checker, padded):
        c.set_scene([WALL], [])
    assert padded.check(ball_state(-0.155)).min_clearance == pytest.approx(
        checker.check(ball_state(-0.155)).min_clearance - 0.03, abs=1e-9)
    with pytest.raises(ValueError, match="padding for link 'ball' must be in"):
        RobotCollisionModel(checker.model.shapes, ("base", "ball"), padding={"ball": -0.1})
