"""Signed distance between two FCL objects, accurate on both sides of contact.

python-fcl 0.7 answers sphere-sphere, sphere-box and capsule-capsule in closed form only without the signed flag;
with ``enable_signed_distance`` every pair goes through libccd's GJK, which is inexact even for separated spheres
and fails badly on rare capsule poses (docs/design-notes.md#signed-distance). Without the flag an overlap returns
-1, so the depth is asked for only then.

The depth is asked of the collision query first. Faces that touch with a tiny tilt put the origin on the boundary of
the Minkowski difference, where FCL's EPA throws a C++ ``std::logic_error`` that python-fcl does not catch: the whole
process aborts. ``collide`` has no such case: no collision is a touch (distance 0), a deepest contact under
:data:`EPA_FLOOR` is that depth, and only deeper overlaps go to EPA, whose depth the collision query can overstate by
centimetres (docs/design-notes.md#signed-distance).
"""

from __future__ import annotations

import functools

import fcl

SEPARATION = fcl.DistanceRequest(enable_nearest_points=True)
PENETRATION = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
OVERLAP = fcl.CollisionRequest(num_max_contacts=16, enable_contact=True)
EPA_FLOOR = 1e-6  # metres: overlaps shallower than this take the collision query's depth instead of EPA's


def signed_distance(
    a: fcl.CollisionObject, b: fcl.CollisionObject, a_solid: fcl.CollisionObject | None = None,
    solver: fcl.GJKSolverType | None = None,
) -> tuple[float, fcl.DistanceResult]:
    """(distance in metres, negative = penetration depth; the result with world-frame witness points).

    ``a_solid`` answers for ``a`` in overlap (the convex hull of a triangle BVH, which has no depth). Pass the
    robot shape as ``a``: a BVH second in the pair reports its witness points swapped. ``solver``: FCL's GJK solver
    for every query (None: libccd, FCL's default, as the env uses); benchmarks compare solvers through it.
    """
    separation, overlap_request, penetration = (SEPARATION, OVERLAP, PENETRATION) if solver is None \
        else _requests(solver)
    result = fcl.DistanceResult()  # FCL only writes into a result when the new distance is smaller
    d = fcl.distance(a, b, separation, result)
    if d > 0.0:
        return d, result
    solid = a_solid or a
    overlap = fcl.CollisionResult()
    if not fcl.collide(solid, b, overlap_request, overlap):
        return 0.0, result  # touching: the distance query's witness points are where
    deepest = max(overlap.contacts, key=lambda c: c.penetration_depth)
    if deepest.penetration_depth < EPA_FLOOR:
        result.min_distance = -deepest.penetration_depth
        result.nearest_points = [deepest.pos.copy(), deepest.pos.copy()]
        return -deepest.penetration_depth, result
    result = fcl.DistanceResult()
    d = fcl.distance(solid, b, penetration, result)
    return d, result


@functools.cache
def _requests(solver: fcl.GJKSolverType) -> tuple[fcl.DistanceRequest, fcl.CollisionRequest, fcl.DistanceRequest]:
    """The three requests of :func:`signed_distance` with ``solver``."""
    return (fcl.DistanceRequest(enable_nearest_points=True, gjk_solver_type=solver),
            fcl.CollisionRequest(num_max_contacts=16, enable_contact=True, gjk_solver_type=solver),
            fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True, gjk_solver_type=solver))
