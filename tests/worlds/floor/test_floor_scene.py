"""Explicit floor scenes: exact placement, round trips, pooled bodies, and errors that name the field."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import CHASSIS_RADIUS, empty_scene

from clutter_gym.sim import pb

LIDAR_X = 0.05  # lidar_link origin ahead of the base frame


def test_explicit_scene_is_placed_exactly(make_env):
    env = make_env()
    wall = {"shape": "box", "size": [0.2, 2.0, 0.5], "position": [1.0, 0.0], "yaw": 0.0}
    post = {"shape": "cylinder", "radius": 0.3, "height": 0.5, "position": [0.0, 1.5]}
    obs, info = env.reset(options={"scene": empty_scene(obstacles=[wall, post])})
    scene = env.unwrapped.scene
    assert [o.shape for o in scene.obstacles] == ["box", "cylinder"]
    # FCL: nearest obstacle is the wall face at x = 0.9, the chassis edge at x = 0.17.
    assert info["min_clearance"] == pytest.approx(0.9 - CHASSIS_RADIUS, abs=1e-6)
    ranges = info["lidar_ranges"]
    angles = env.unwrapped.sensors[0].config.angles
    front = np.argmin(np.abs(angles))
    assert ranges[front] == pytest.approx(0.9 - LIDAR_X, abs=1e-3)
    left = np.argmin(np.abs(angles - np.pi / 2))
    # beam from (0.05, 0) along +y meets the circle x^2 + (y - 1.5)^2 = 0.3^2
    expected = 1.5 - np.sqrt(0.3**2 - LIDAR_X**2)
    assert ranges[left] == pytest.approx(expected, abs=1e-3)


def test_scene_round_trip_reproduces_the_layout(make_env):
    a, b = make_env(), make_env()
    obs_a, _ = a.reset(seed=21)
    obs_b, _ = b.reset(options={"scene": a.unwrapped.scene.to_dict()})
    for key in obs_a:
        np.testing.assert_allclose(obs_a[key], obs_b[key], atol=1e-9)


def server_body_ids(cid: int) -> list[int]:
    """Every body id in the world as the physics server lists it (pybullet's client lists bodies made in batches
    only once it has synced)."""
    pb.syncBodyInfo(physicsClientId=cid)
    return sorted(pb.getBodyUniqueId(i, physicsClientId=cid) for i in range(pb.getNumBodies(physicsClientId=cid)))


def test_new_layouts_move_pooled_bodies_without_reloading(make_env):
    env = make_env()
    env.reset(seed=0)
    unwrapped = env.unwrapped
    robot = unwrapped.robot.body
    for _ in range(50):
        env.reset()
    cid = unwrapped.sim._cid
    bodies = server_body_ids(cid)
    # ground + 4 walls + robot + goal marker + pooled obstacles: nothing else is in the world
    assert len(bodies) == 7 + unwrapped.arena.pool_size
    assert unwrapped.sim.body_ids() == bodies
    assert unwrapped.robot.body == robot
    pool = unwrapped.arena._pool
    assert pool.size <= len(unwrapped.scene.obstacles) + pool.max_parked  # parked bodies are capped
    env.reset(seed=0)
    n_bodies = len(server_body_ids(cid))
    for _ in range(30):  # the same layout again: the pool has every shape already
        env.reset(seed=0)
    assert len(server_body_ids(cid)) == n_bodies


@pytest.mark.parametrize(
    "scene, pattern",
    [
        ([1, 2], r"scene must be a dict"),
        ({"start": [0, 0, 0]}, r"scene.goal is required"),
        ({"start": [0, 0, 0], "goal": [1, 1], "walls": []}, r"unknown keys \['walls'\]"),
        ({"start": [0, 0], "goal": [1, 1]}, r"scene.start must be a list of 3 numbers"),
        ({"start": [0, 0, 0], "goal": [9, 0]}, r"scene.goal must lie inside the arena"),
        ({"start": [2.9, 0, 0], "goal": [1, 1]}, r"scene.start must lie inside the arena: \|x\|, \|y\| <= 2.830"),
        ({"start": [0, float("nan"), 0], "goal": [1, 1]}, r"scene.start must be finite"),
        ({"start": [0, 0, 0], "goal": [1, 1], "obstacles": {"shape": "box"}}, r"scene.obstacles must be a list"),
        ({"start": [0, 0, 0], "goal": [1, 1], "obstacles": [{"shape": "sphere"}]},
         r"scene.obstacles\[0\].shape must be one of \('box', 'cylinder'\)"),
        ({"start": [0, 0, 0], "goal": [1, 1],
          "obstacles": [{"shape": "box", "size": [1, -1, 1], "position": [2, 2]}]},
         r"scene.obstacles\[0\].size y must be in \(0, 6.0\] m"),
        ({"start": [0, 0, 0], "goal": [1, 1],
          "obstacles": [{"shape": "cylinder", "radius": 0.2, "position": [2, 2]}]},
         r"scene.obstacles\[0\] is missing \['height'\]"),
        ({"start": [0, 0, 0], "goal": [1, 1],
          "obstacles": [{"shape": "cylinder", "radius": 0.2, "height": 0.5, "position": [2, 2], "yaw": 1}]},
         r"scene.obstacles\[0\] has unknown keys \['yaw'\]"),
        ({"start": [0, 0, 0], "goal": [1, 1],
          "obstacles": [{"shape": "box", "size": [1, 1, 1], "position": [0.3, 0]}]},
         r"scene.start \(0.0, 0.0\) is -0.200 m from the nearest obstacle"),
    ],
)
def test_malformed_scenes_raise_naming_the_field(scene, pattern, make_env):
    env = make_env()
    with pytest.raises(ValueError, match=pattern):
        env.reset(options={"scene": scene})


def test_unknown_reset_option_is_named(make_env):
    with pytest.raises(ValueError, match=r"unknown reset options \['layout'\]; allowed: \['scene'\]"):
        make_env().reset(options={"layout": {}})


def test_numpy_numbers_and_arrays_are_accepted_in_scenes():
    """A scene built with numpy (float32 heights, array positions, int64 sizes) parses as its plain-number twin."""
    from clutter_gym.worlds.floor.scene import parse_scene

    plain = {"obstacles": [{"shape": "box", "size": [0.4, 0.4, 0.5], "position": [1.0, 1.0], "z": 0.0},
                           {"shape": "cylinder", "radius": 0.2, "height": 1.0, "position": [-1.0, 1.0]}],
             "start": [-2.0, -2.0, 0.0], "goal": [2.0, 2.0]}
    with_numpy = {"obstacles": [{"shape": "box", "size": np.array([0.4, 0.4, 0.5]), "position": np.array([1.0, 1.0]),
                                 "z": np.float32(0.0)},
                                {"shape": "cylinder", "radius": np.float64(0.2), "height": np.int64(1),
                                 "position": (np.float32(-1.0), np.float32(1.0))}],
                  "start": np.array([-2.0, -2.0, 0.0]), "goal": np.array([2.0, 2.0])}
    expected, got = parse_scene(plain, 6.0, CHASSIS_RADIUS), parse_scene(with_numpy, 6.0, CHASSIS_RADIUS)
    assert got.obstacles == expected.obstacles
    assert got.start == expected.start and got.goal == expected.goal
    with pytest.raises(ValueError, match=r"scene.obstacles\[0\].position must be a list of 2 numbers"):
        parse_scene({**plain, "obstacles": [{**plain["obstacles"][0], "position": np.zeros((2, 2))}]}, 6.0,
                     CHASSIS_RADIUS)
