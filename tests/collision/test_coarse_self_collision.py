"""Self-collision at the coarse levels (sphere, spheres, primitive) is the robot's, not its coarse shapes': every
hit of theirs is confirmed with the convex level's shapes, over the convex level's ACM."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from clutter_gym.collision import (
    RobotCollisionModel,
    UrdfKinematics,
    build_link_shapes,
    load_acm,
    load_collision_elements,
)
from clutter_gym.collision.confirm import PairConfirmer
from clutter_gym.collision.fidelity import COARSE_LEVELS
from clutter_gym.robots import PandaArm

URDF = PandaArm().urdf_path
KIN = UrdfKinematics(URDF)
N_CONFIGS = 500


@pytest.fixture(scope="module")
def random_poses():
    """Link poses of seeded random Panda configurations, uniform within the joint limits (fingers included)."""
    q = np.random.default_rng(11).uniform(KIN.lower, KIN.upper, size=(N_CONFIGS, len(KIN.joints)))
    frames = KIN.forward(q)
    positions = np.stack([frames[name][:, :3, 3] for name in KIN.links], axis=1)
    rotations = np.stack([frames[name][:, :3, :3] for name in KIN.links], axis=1)
    return positions, rotations


def verdicts(level: str, padding: float, poses) -> list[tuple[str, str] | None]:
    model = RobotCollisionModel.from_urdf(URDF, level, KIN.links, padding)
    out = []
    for positions, rotations in zip(*poses):
        model.sync(positions, rotations)
        out.append(model.self_collision())
    return out


@functools.lru_cache(maxsize=2)
def convex_shapes(padding: float) -> RobotCollisionModel:
    return RobotCollisionModel.from_urdf(URDF, "convex", KIN.links, padding, self_collision=False)


def touching_at_convex(pair: tuple[str, str], positions, rotations, padding: float) -> bool:
    """Whether the convex shapes of the two links touch, measured pair by pair (no ACM, no confirmer)."""
    model = convex_shapes(padding)
    model.sync(positions, rotations)
    links = [s.link for s in model.shapes]
    return any(model._pair_distance(i, j) <= 0.0 for i, a in enumerate(links) for j, b in enumerate(links)
               if (a, b) == pair)


@pytest.mark.parametrize("padding", [0.0, 0.01])
def test_coarse_levels_report_self_collision_where_convex_does(padding, random_poses):
    """sphere and primitive enclose the convex shapes, so a pair convex finds touching is a coarse hit as well and
    the verdicts agree; spheres' sphere sets enclose the meshes, not their hulls, so it can only report less. With
    several pairs touching, the levels may name different ones: each named pair must touch at convex."""
    convex = verdicts("convex", padding, random_poses)
    in_collision = np.array([v is not None for v in convex])
    assert 0.05 < in_collision.mean() < 0.5  # folded arms among the samples
    for level in COARSE_LEVELS:
        coarse = verdicts(level, padding, random_poses)
        reported = np.array([v is not None for v in coarse])
        false_hits = np.flatnonzero(reported & ~in_collision)
        assert false_hits.size == 0, f"{level} reports self-collision convex does not in {false_hits.size} configs"
        if level != "spheres":
            np.testing.assert_array_equal(reported, in_collision, err_msg=level)
        for k in np.flatnonzero(reported)[:50]:
            assert touching_at_convex(coarse[k], random_poses[0][k], random_poses[1][k], padding), (level, k)


def test_coarse_levels_check_the_convex_acm():
    enabled = load_acm(URDF, "convex").enabled
    for level in COARSE_LEVELS:
        assert load_acm(URDF, level).enabled == enabled
        model = RobotCollisionModel.from_urdf(URDF, level, KIN.links)
        assert sorted({tuple(sorted(p)) for p in model._self_links}) == list(enabled), level


def test_the_confirmer_moves_only_the_shapes_of_the_pair_it_is_asked_about():
    """What keeps a coarse level's cost where no coarse pair touches: nothing of the convex shapes moves."""
    shapes = build_link_shapes(load_collision_elements(URDF), "convex")
    confirmer = PairConfirmer(shapes, KIN.links)
    with pytest.raises(RuntimeError, match="set_link_poses"):
        confirmer.collide("panda_link5", "panda_link7")
    frames = KIN.forward(np.zeros((1, len(KIN.joints))))
    confirmer.set_link_poses(np.stack([frames[n][0, :3, 3] for n in KIN.links]),
                             np.stack([frames[n][0, :3, :3] for n in KIN.links]))
    assert not any(confirmer._placed)
    confirmer.collide("panda_link5", "panda_link7")
    assert {s.link for s, placed in zip(shapes, confirmer._placed) if placed} == {"panda_link5", "panda_link7"}


@pytest.mark.parametrize("level", ["primitive", "convex"])
def test_padding_does_not_reach_self_collision(level, random_poses):
    """Padding is a margin against the world; the ACM is sampled on the unpadded shapes, and neighbouring links sit
    a few centimetres apart in every pose."""
    assert verdicts(level, 0.03, random_poses) == verdicts(level, 0.0, random_poses)
