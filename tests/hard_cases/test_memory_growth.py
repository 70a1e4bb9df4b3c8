"""Memory while an env stays open: flat across resets, whatever scenes the user sends.

pybullet frees neither a shape a body has used nor all of a removed body; the Sim shares shapes between bodies of
one size and the env rebuilds its world (``Sim.clear``) when too much has piled up. python-fcl loses a little of
every object it frees; the checker reuses them. Resident memory is read from
/proc; the bounds sit far below what the leak cost before (about 7 KB per ClutterReach reset and 240 KB per
ClutterNav reset with five new cylinder sizes) and far above the allocator's noise.
"""

from __future__ import annotations

import sys

import gymnasium as gym
import numpy as np
import pytest

import clutter_gym.sim.core
from benchmarks.hard_cases.scenes.memory import new_sizes_scene, resident_mib
from clutter_gym.collision.obstacles import ObstacleObjects, obstacle_object
from clutter_gym.worlds import ClutterSpec, sample_scene

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/statm")


def test_obstacle_objects_are_reused_and_placed_as_new_ones_would_be():
    """python-fcl loses 31 bytes of every CollisionObject it frees: a layout seen again makes no new object."""
    rng = np.random.default_rng(0)
    a, b = (sample_scene(rng, ClutterSpec(), 0.17).obstacles for _ in range(2))
    cache = ObstacleObjects()
    first = cache.place(a)
    cache.place(b)
    again = cache.place(a)
    assert all(x is y for x, y in zip(first, again))
    for o, obj in zip(a, again):
        new = obstacle_object(o)
        np.testing.assert_array_equal(obj.getTranslation(), new.getTranslation())
        np.testing.assert_array_equal(obj.getRotation(), new.getRotation())


def test_generated_layouts_share_shapes_and_hold_memory_flat():
    env = gym.make("ClutterReach-v1")
    env.reset(seed=0)
    sim = env.unwrapped.sim
    for _ in range(300):  # warm up: the pool and the shape cache fill
        env.reset()
    shapes, before = len(sim.record.shapes), resident_mib()
    for _ in range(1000):
        env.reset()
    growth = resident_mib() - before
    env.close()
    assert len(sim.record.shapes) <= shapes + 2  # 27 box and 9 cylinder sizes, the table: a few late first draws
    assert growth < 2, f"{growth:.1f} MiB over 1,000 resets"


def test_new_sizes_every_reset_rebuild_the_world_and_hold_memory_flat(monkeypatch):
    monkeypatch.setattr(clutter_gym.sim.core, "MAX_SHAPES", 60)  # a rebuild every 12 resets instead of every ~100
    env = gym.make("ClutterNav-v1")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(100):
        env.reset(options={"scene": new_sizes_scene(rng)})
    before = resident_mib()
    for _ in range(300):
        env.reset(options={"scene": new_sizes_scene(rng)})
    growth = resident_mib() - before
    assert len(env.unwrapped.sim.record.shapes) <= 60 + 5
    env.close()
    assert growth < 8, f"{growth:.1f} MiB over 300 resets"


def rollout(env: gym.Env, scene: dict, seed: int) -> list[np.ndarray]:
    obs, _ = env.reset(seed=seed, options={"scene": scene})
    trace = [obs["lidar"]]
    actions = np.random.default_rng(1)
    for _ in range(40):
        obs, *_ = env.step(actions.uniform(-1, 1, 2).astype(np.float32))
        trace.append(np.concatenate([obs["lidar"], obs["goal"]]))
    return trace


def test_a_rebuilt_world_runs_as_a_fresh_one(monkeypatch):
    """The same seed, scene and actions give the same trajectory after a rebuild as in a fresh env, with the same
    body ids and names."""
    scene = new_sizes_scene(np.random.default_rng(5))
    fresh = gym.make("ClutterNav-v1")
    expected = rollout(fresh, scene, seed=3)
    names = fresh.unwrapped.sim.body_names()
    fresh.close()

    monkeypatch.setattr(clutter_gym.sim.core, "MAX_SHAPES", 8)
    env = gym.make("ClutterNav-v1")
    rng = np.random.default_rng(0)
    for _ in range(2):
        env.reset(options={"scene": new_sizes_scene(rng)})
    assert env.unwrapped.sim.needs_rebuild
    got = rollout(env, scene, seed=3)
    assert not env.unwrapped.sim.needs_rebuild
    assert env.unwrapped.sim.body_names() == names
    env.close()
    for a, b in zip(expected, got):
        np.testing.assert_array_equal(a, b)


def test_make_and_close_cycles_give_their_memory_back():
    """The target is under 50 MB over 1,000 cycles; 200 cycles measured 0.9 MiB, the bound is that target's share."""
    for _ in range(20):  # warm-up: imports, caches and the allocator's first arenas
        gym.make("ClutterNav-v1").close()
    before = resident_mib()
    for seed in range(200):
        env = gym.make("ClutterNav-v1")
        env.reset(seed=seed)
        env.close()
    growth = resident_mib() - before
    assert growth < 10, f"{growth:.1f} MiB over 200 make/close cycles"


def _connected_clients() -> list[int]:
    import pybullet as pb

    return [c for c in range(4096) if pb.isConnected(physicsClientId=c)]


@pytest.mark.parametrize("env_id", ["ClutterNav-v1", "ClutterReach-v1", "ClutterFly-v1"])
def test_an_env_dropped_without_close_gives_its_physics_server_back(env_id):
    """Notebooks and evaluation loops drop envs unclosed; each one kept its pybullet server (29 MiB a ClutterNav or
    ClutterFly env, 86 MiB a ClutterReach one) until the Sim got a finalizer. The bound is a small fraction of one
    leaked server per env, far above the allocator's noise."""
    import gc

    before_clients = _connected_clients()
    for seed in range(3):  # warm-up: caches, compiled kernels and the allocator's first arenas
        env = gym.make(env_id)
        env.reset(seed=seed)
        del env
    gc.collect()
    before = resident_mib()
    for seed in range(3, 23):
        env = gym.make(env_id)
        env.reset(seed=seed)
        del env
        gc.collect()
    growth = resident_mib() - before
    assert _connected_clients() == before_clients
    assert growth < 20, f"{growth:.1f} MiB over 20 envs dropped without close()"


def test_the_finalizer_runs_once_and_close_still_works_after_it():
    """close() and garbage collection share one finalizer: closing twice, then dropping, disconnects once."""
    import gc

    sim = clutter_gym.sim.core.Sim()
    client = sim.client_id
    finalizer = sim._finalizer
    sim.close()
    sim.close()
    assert sim.client_id == -1 and not finalizer.alive
    del sim
    gc.collect()
    assert client not in _connected_clients()
