"""The ``auto`` fidelity level: a mesh element's hull where the hull is the mesh to within a tolerance, its
triangles elsewhere; clearance equal to ``mesh``'s within that tolerance."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from clutter_gym.collision import CollisionChecker, RobotCollisionModel, UrdfKinematics, build_link_shapes
from clutter_gym.collision.fidelity import AUTO_HULL_TOLERANCE, hull_gap
from clutter_gym.datatypes import Obstacle
from clutter_gym.robots import PandaArm
from clutter_gym.urdf.geometry import CollisionElement

URDF = PandaArm().urdf_path
KIN = UrdfKinematics(URDF)
FINGERS = [0.02, 0.02]


def l_shape() -> trimesh.Trimesh:
    """Two unit-high boxes forming an L in the xy plane: [0, 2] x [0, 1] and [0, 1] x [1, 2]. Its hull bridges the
    inner corner with a face from (2, 1) to (1, 2), whose midpoint (1.5, 1.5) lies 0.5 from both inner faces: the
    largest gap between the hull and the L."""
    a = trimesh.creation.box((2.0, 1.0, 1.0), trimesh.transformations.translation_matrix((1.0, 0.5, 0.5)))
    b = trimesh.creation.box((1.0, 1.0, 1.0), trimesh.transformations.translation_matrix((0.5, 1.5, 0.5)))
    return trimesh.util.concatenate([a, b])


def element(mesh: trimesh.Trimesh) -> CollisionElement:
    return CollisionElement("link", "mesh", tuple(mesh.extents.tolist()), np.zeros(3), (0.0, 0.0, 0.0, 1.0), mesh)


def test_hull_gap_is_zero_for_a_convex_mesh_and_the_analytic_gap_for_an_l():
    assert hull_gap(trimesh.creation.box((0.3, 0.2, 0.1))) < 1e-9
    assert hull_gap(trimesh.creation.icosphere(2, 0.1)) < 1e-9
    # sampled: the largest gap found is at most the true one, and 1,000 samples on the hull come close to it
    assert 0.45 < hull_gap(l_shape()) <= 0.5 + 1e-9


def test_auto_keeps_triangles_only_where_the_hull_strays():
    convex_box = element(trimesh.creation.box((0.3, 0.2, 0.1)))
    [box_shape, l_shape_shape] = build_link_shapes([convex_box, element(l_shape())], "auto")
    assert box_shape.kind == "convex"
    assert l_shape_shape.kind == "mesh" and l_shape_shape.hull is not None  # the hull answers depth, as at mesh


def test_auto_on_the_panda_is_the_hull_except_the_concave_link6():
    """link6's OBJ has a notch its hull fills (about 18 mm deep); the other links' OBJs are convex to 0.35 mm."""
    shapes = RobotCollisionModel.from_urdf(URDF, "auto", KIN.links, self_collision=False).shapes
    kinds = {s.link: s.kind for s in shapes}
    assert kinds.pop("panda_link6") == "mesh"
    assert set(kinds.values()) == {"convex"}


@pytest.mark.parametrize("obstacle", [
    Obstacle("box", (0.3, 0.3, 0.3), (0.45, 0.1), 0.3, 0.0),
    Obstacle("cylinder", (0.16, 0.16, 0.6), (0.35, -0.3), 0.0, 0.0),
], ids=["box", "cylinder"])
def test_auto_clearance_equals_the_mesh_within_the_tolerance(obstacle):
    checkers = []
    for level in ("auto", "mesh"):
        model = RobotCollisionModel.from_urdf(URDF, level, KIN.links, self_collision=False)
        checkers.append(CollisionChecker(model, "panda_link0", clearance_range=0.5, fixed_links=("panda_link0",)))
        checkers[-1].set_scene([obstacle], [])
    rng = np.random.default_rng(4)
    differences = []
    for _ in range(300):
        q = rng.uniform(KIN.lower[:7], KIN.upper[:7])
        frames = KIN.forward(np.concatenate([q, FINGERS])[None])
        positions = np.stack([frames[n][0, :3, 3] for n in KIN.links])
        rotations = np.stack([frames[n][0, :3, :3] for n in KIN.links])
        per_link = []
        for checker in checkers:
            checker.model.sync(positions, rotations)
            per_link.append(checker.clearance()[0])
        auto, mesh = per_link
        near = (mesh > 0.0) & (mesh < 0.15)
        differences.extend(auto[near] - mesh[near])
    differences = np.array(differences)
    assert len(differences) > 30
    # The hull encloses the mesh: less clearance by at most the hull's gap, plus GJK's error. GJK is also why a hull
    # can read more clearance than the triangles: against a cylinder by up to 0.7 mm over 2,000 random poses here
    # (the convex level shows the same), against a box by under 0.03 mm.
    assert differences.min() >= -AUTO_HULL_TOLERANCE - 2e-4
    assert differences.max() <= 1e-3
    assert np.abs(differences).mean() < 1e-5  # equal almost everywhere; the convex level is off by 0.03-0.05 mm
