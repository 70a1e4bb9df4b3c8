"""Seeded trajectories of every env and registered robot, against the ones recorded in tests/data/trajectories.npz.

A change that should not change what an env does (a refactor, a speed-up) must leave these alone: the same seed and
actions give the same observations, rewards, costs and clearances. The tolerance (relative 1e-7) admits only the
last-bit differences another CPU's vector units can give over a short rollout; any change of behaviour moves these
numbers by far more. A change that means to alter trajectories re-records them, and says so in its commit and in
the env's version history:

    python tests/test_recorded_trajectories.py      # rewrites tests/data/trajectories.npz
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import clutter_gym  # noqa: F401  (registers the envs)

RECORDED = Path(__file__).resolve().parent / "data" / "trajectories.npz"
STEPS = 25
#: name -> (env id, gym.make arguments): each registered robot on its env, the LIDAR on the flyer and a noise
#: profile (its sensor, action and dynamics channels) on the ground robot.
CASES = {
    "nav-diffbot": ("ClutterNav-v1", {}),
    "nav-husky": ("ClutterNav-v1", {"robot": "husky"}),
    "nav-omnibot": ("ClutterNav-v1", {"robot": "omnibot"}),
    "nav-diffbot-nominal": ("ClutterNav-v1", {"noise": "nominal", "safety_horizon": 0.5}),
    "reach-panda": ("ClutterReach-v1", {}),
    "reach-kuka_iiwa": ("ClutterReach-v1", {"robot": "kuka_iiwa"}),
    "reach-xarm6": ("ClutterReach-v1", {"robot": "xarm6"}),
    "fly-quadrotor-lidar": ("ClutterFly-v1", {"sensors": ("imu", "lidar")}),
}


def trajectory(env_id: str, kwargs: dict) -> np.ndarray:
    """One row per step (the reset first): every observation entry, then reward, cost and min_clearance."""
    env = gym.make(env_id, **kwargs)
    try:
        obs, _ = env.reset(seed=5)
        actions = np.random.default_rng(11).uniform(-1, 1, size=(STEPS, *env.action_space.shape))
        rows = [np.concatenate([np.ravel(obs[k]) for k in sorted(obs)] + [np.zeros(3)])]
        for action in actions:
            obs, reward, terminated, truncated, info = env.step(action.astype(np.float32))
            rows.append(np.concatenate([np.ravel(obs[k]) for k in sorted(obs)]
                                       + [np.array([reward, info["cost"], info["min_clearance"]])]))
            if terminated or truncated:
                break
        return np.array(rows, dtype=np.float64)
    finally:
        env.close()


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_seeded_trajectory_is_the_recorded_one(name):
    recorded = np.load(RECORDED)
    assert name in recorded.files, f"{name} is not recorded; run python tests/test_recorded_trajectories.py"
    np.testing.assert_allclose(trajectory(*CASES[name]), recorded[name], rtol=1e-7, atol=1e-9,
                               err_msg=f"{name}'s seeded trajectory changed")


def test_every_registered_robot_is_recorded():
    from clutter_gym.robots.registry import GROUND_KINDS, registered

    kinds = {"ClutterNav-v1": (GROUND_KINDS, "diffbot"), "ClutterReach-v1": (("arm",), "panda"),
             "ClutterFly-v1": (("multirotor",), "quadrotor")}
    recorded = {(env, kwargs.get("robot", kinds[env][1])) for env, kwargs in CASES.values()}
    assert {(env, robot) for env, (kinds_, _) in kinds.items() for kind in kinds_ for robot in registered(kind)} <= (
        recorded)


if __name__ == "__main__":
    from clutter_gym.util.atomic import atomic_path

    with atomic_path(RECORDED) as tmp, tmp.open("wb") as f:
        np.savez_compressed(f, **{name: trajectory(*case) for name, case in CASES.items()})
    print(RECORDED)
