"""Training on a fixed pool of layouts: seeded, drawn from its own seeds only, and out of the way of user scenes."""

from __future__ import annotations

import numpy as np
import pytest

from clutter_gym.training.config import TrainConfig
from clutter_gym.training.layout_pool import POOL_SEEDS, LayoutPool
from clutter_gym.training.vec_env import build_vec_env


def layouts(env: LayoutPool, n: int) -> list[tuple]:
    out = []
    for _ in range(n):
        env.reset()
        out.append(env.unwrapped.scene)
    return out


def test_pool_resets_cycle_through_its_own_layouts(make_env):
    env = LayoutPool(make_env("ClutterReach-v1"), n_layouts=3)
    env.reset(seed=7)
    assert len(env.pool) == 3 and np.all(env.pool >= POOL_SEEDS)
    seen = layouts(env, 30)
    assert len(set(seen)) == 3  # only the pool's layouts, and all of them in 30 draws (p of missing one < 1e-5)


def test_pool_is_fixed_by_the_first_seed(make_env):
    a = LayoutPool(make_env("ClutterReach-v1"), n_layouts=4)
    b = LayoutPool(make_env("ClutterReach-v1"), n_layouts=4)
    a.reset(seed=3)
    b.reset(seed=3)
    assert np.array_equal(a.pool, b.pool) and layouts(a, 6) == layouts(b, 6)
    b.reset(seed=4)
    assert not np.array_equal(a.pool, b.pool)


def test_an_explicit_scene_passes_through(make_env):
    env = LayoutPool(make_env("ClutterReach-v1"), n_layouts=2)
    scene = {"obstacles": [], "start": [0.0, -0.78, 0.0, -2.36, 0.0, 1.57, 0.78], "target": [0.4, 0.0, 0.3]}
    env.reset(seed=0, options={"scene": scene})
    assert env.unwrapped.scene.target == (0.4, 0.0, 0.3)


@pytest.mark.parametrize("n", [0, -1, 2.5])
def test_pool_size_must_be_a_positive_integer(make_env, n):
    with pytest.raises(ValueError, match="n_layouts must be an integer >= 1"):
        LayoutPool(make_env("ClutterReach-v1"), n_layouts=n)


def test_training_envs_share_out_the_pool():
    config = TrainConfig(env_id="ClutterReach-v1", n_envs=2, env_workers=1, train_layouts=5)
    assert config.layouts_per_env == 3
    venv = build_vec_env(config, seed=0)
    try:
        venv.reset()
        pools = [env.env.env.pool for env in venv.envs]  # EpisodeStats(Monitor(LayoutPool(...)))
        assert [len(p) for p in pools] == [3, 3]  # ceil(5 / 2) each
        assert not set(pools[0]) & set(pools[1])
    finally:
        venv.close()
    with pytest.raises(ValueError, match="train_layouts"):
        TrainConfig(train_layouts=-1)
