"""The obstacle pool makes the bodies a scene lacks in batches, one shape at a time: every body gets its true id,
and contacts are solved as if each body had been made on its own, in scene order."""

from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest

from clutter_gym.datatypes import Obstacle
from clutter_gym.sim import Sim
from clutter_gym.worlds.pool import ObstaclePool


def mixed_obstacles(n: int, seed: int) -> tuple[Obstacle, ...]:
    """``n`` boxes and cylinders of five shapes, interleaved, at random places in a 20 m square."""
    rng = np.random.default_rng(seed)
    shapes = [("box", (0.2, 0.3, 0.5)), ("cylinder", (0.2, 0.2, 0.5)), ("box", (0.1, 0.1, 0.4)),
              ("cylinder", (0.3, 0.3, 0.4)), ("box", (0.4, 0.2, 0.3))]
    return tuple(Obstacle(*shapes[k % len(shapes)], tuple(rng.uniform(-10, 10, 2)), float(rng.uniform(-3, 3)))
                 for k in range(n))


def server_body_ids(cid: int) -> list[int]:
    """Every body id in the world as the physics server lists it (the client learns of batched bodies on a sync)."""
    pb.syncBodyInfo(physicsClientId=cid)
    return sorted(pb.getBodyUniqueId(i, physicsClientId=cid) for i in range(pb.getNumBodies(physicsClientId=cid)))


def test_bodies_made_in_batches_after_removals_have_their_true_ids():
    """pybullet numbers a batch as if its ids were consecutive, but reuses removed ids first: a scene placed after
    the pool deleted bodies still gets, for each obstacle, the body standing at that obstacle."""
    sim = Sim(visuals=False)
    try:
        pool = ObstaclePool(sim, max_parked=10)
        for n, seed in ((300, 0), (5, 1), (400, 2), (20, 3), (250, 4)):
            obstacles = mixed_obstacles(n, seed)
            bodies = pool.place(obstacles)
            assert len(set(bodies)) == len(bodies)
            for o, body in zip(obstacles, bodies):
                position, quaternion = pb.getBasePositionAndOrientation(body, physicsClientId=sim.client_id)
                np.testing.assert_allclose(position, o.centre, atol=1e-12)
                yaw = pb.getEulerFromQuaternion(quaternion)[2]
                assert yaw == pytest.approx(np.arctan2(np.sin(o.yaw), np.cos(o.yaw)), abs=1e-12)
            assert sim.body_ids() == server_body_ids(sim.client_id)
    finally:
        sim.close()


STACK = (Obstacle("box", (1.0, 1.0, 1.0), (-3.0, 3.0)), Obstacle("box", (1.0, 1.2, 1.0), (-0.52, 0.0)),
         Obstacle("box", (1.0, 1.0, 1.0), (0.52, 0.1)))


def drop_across(scenes: list[tuple[Obstacle, ...]]) -> tuple:
    """Pose after 2 s of a box dropped across the last two obstacles of :data:`STACK`, placed by the pool as
    ``scenes`` in turn (the last one is :data:`STACK`)."""
    sim = Sim()
    try:
        sim.add_ground(10.0)
        pool = ObstaclePool(sim)
        for scene in scenes:
            pool.place(scene)
        cid = sim.client_id
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(0.4, 0.3, 0.2), physicsClientId=cid)
        body = pb.createMultiBody(1.0, shape, -1, (0.03, 0.0, 1.3), pb.getQuaternionFromEuler((0.1, 0.2, 0.3)),
                                  physicsClientId=cid)
        sim.step(240)
        return pb.getBasePositionAndOrientation(body, physicsClientId=cid)
    finally:
        sim.close()


def test_bodies_made_in_batches_solve_contacts_in_scene_order():
    """Placed at once, the two boxes of one size are made in one call, before the other; Bullet solves contacts in
    broad-phase order, which ``Sim.order_broadphase`` sets to scene order: the dropped box lands exactly as when
    the scene grows one obstacle at a time, each body made in turn (made in shape order, it lands 0.3 mm away)."""
    one_by_one = drop_across([STACK[:k] for k in range(1, len(STACK) + 1)])
    assert drop_across([STACK]) == one_by_one
