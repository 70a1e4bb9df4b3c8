"""Signed distance between two FCL objects, accurate on both sides of contact.

python-fcl 0.7 answers sphere-sphere, sphere-box and capsule-capsule in closed form only without the signed flag;
with ``enable_signed_distance`` every pair goes through libccd's GJK, which is inexact even for separated spheres
and fails badly on rare capsule poses (docs/design-notes.md#signed-distance). Without the flag an overlap returns
-1, so the depth is asked for only then, with the signed request (EPA).
"""

from __future__ import annotations

import fcl

SEPARATION = fcl.DistanceRequest(enable_nearest_points=True)
PENETRATION = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)


def signed_distance(
    a: fcl.CollisionObject, b: fcl.CollisionObject, a_solid: fcl.CollisionObject | None = None
) -> tuple[float, fcl.DistanceResult]:
    """(distance in metres, negative = penetration depth; the result with world-frame witness points).

    ``a_solid`` answers for ``a`` in overlap (the convex hull of a triangle BVH, which has no depth). Pass the
    robot shape as ``a``: a BVH second in the pair reports its witness points swapped.
    """
    result = fcl.DistanceResult()  # FCL only writes into a result when the new distance is smaller
    d = fcl.distance(a, b, SEPARATION, result)
    if d <= 0.0:
        result = fcl.DistanceResult()
        d = fcl.distance(a_solid or a, b, PENETRATION, result)
    return d, result
