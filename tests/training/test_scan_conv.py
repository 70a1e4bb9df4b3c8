"""A student whose LIDAR is read by a convolution over the beams (``ppo.scan_conv``): the features see a shifted
scan as shifted maps, the settings it cannot have are refused by name, and its run trains, loads and acts as any
other."""

from __future__ import annotations

import numpy as np
import pytest
import torch as th
from gymnasium import spaces

from clutter_gym.training import load
from clutter_gym.training.config import config_for
from clutter_gym.training.privileged import PrivilegedCriticPolicy
from clutter_gym.training.scan_features import KERNEL, ScanFeatures
from clutter_gym.training.train import start, train

SMALL = {"arena_size": 3.0, "obstacle_density": 0.05, "n_rays": 16, "sensors": ["lidar"], "reverse": False,
         "observe_bearing": True, "max_episode_steps": 60, "subgoal_lookahead": 0.0}
BASE = {"teacher": {"name": "planner"}, "env_kwargs": SMALL, "timesteps": 2400, "residual_space": "waypoint",
        "action_bins": 5, "distill": {"rounds": 2, "round_steps": 1000, "warmup_steps": 400}}


@pytest.mark.parametrize("shape", [(24,), (3, 24)])
def test_a_scan_shifted_by_some_beams_gives_the_same_maps_shifted(shape):
    space = spaces.Dict({"lidar": spaces.Box(0, 1, shape), "goal": spaces.Box(-1, 1, (2,))})
    th.manual_seed(0)
    features = ScanFeatures(space, ["lidar", "goal"], widths=[4, 4])
    width, beams = 4, shape[-1]
    assert features.features_dim == width * beams + 2
    scan = th.rand(1, *shape)
    goal = th.tensor([[0.5, -0.5]])
    with th.no_grad():
        plain = features({"lidar": scan, "goal": goal})
        shifted = features({"lidar": th.roll(scan, 3, dims=-1), "goal": goal})
    maps, moved = plain[0, :-2].reshape(width, beams), shifted[0, :-2].reshape(width, beams)
    edge = 2 * (KERNEL // 2)  # two layers of zero padding reach this far in from each end
    np.testing.assert_allclose(moved[:, 3 + edge:beams - edge], maps[:, edge:beams - 3 - edge], atol=1e-6)
    assert not th.allclose(moved, maps)  # and the maps do depend on where the scan's features lie
    np.testing.assert_array_equal(plain[0, -2:], goal[0])  # the other entries pass through flattened


@pytest.mark.parametrize(("settings", "message"), [
    ({"teacher": {}, "residual_space": "action"}, "ppo.scan_conv is a distilled student's"),
    ({"frame_stack": 4}, "ppo.scan_conv is a distilled student's"),
    ({"ppo": {"scan_conv": [0]}}, r"ppo.scan_conv must be at most 8 layer widths in \[1, 256\]"),
    ({"ppo": {"scan_conv": [8] * 9}}, r"ppo.scan_conv must be at most 8 layer widths in \[1, 256\]"),
])
def test_what_a_scan_convolution_cannot_have_is_refused_by_name(settings, message):
    with pytest.raises(ValueError, match=message):
        config_for("ClutterNav-v1", {**BASE, **settings, "ppo": {"scan_conv": [8], **settings.get("ppo", {})}})


def test_a_policy_reading_no_lidar_refuses_the_convolution():
    space = spaces.Dict({"goal": spaces.Box(-1, 1, (2,))})
    with pytest.raises(ValueError, match=r"ppo.scan_conv needs the entries \['lidar'\]"):
        ScanFeatures(space, ["goal"], widths=[4])


def test_a_memory_laid_out_beam_by_beam_is_read_as_a_second_channel_of_the_scan():
    space = spaces.Dict({"lidar": spaces.Box(0, 1, (16,)), "memory": spaces.Box(0, 1, (16,)),
                         "goal": spaces.Box(-1, 1, (2,))})
    features = ScanFeatures(space, ["goal", "lidar", "memory"], widths=[4], scans=["lidar", "memory"])
    assert features.conv[0].in_channels == 2 and features.features_dim == 4 * 16 + 2
    obs = {"lidar": th.rand(1, 16), "memory": th.rand(1, 16), "goal": th.zeros(1, 2)}
    with th.no_grad():
        assert not th.allclose(features(obs), features(dict(obs, memory=th.ones(1, 16))))
    wrong = spaces.Dict({**space.spaces, "memory": spaces.Box(0, 1, (20,))})
    with pytest.raises(ValueError, match=r"their beams differ: \[16, 20\]"):
        ScanFeatures(wrong, ["goal", "lidar", "memory"], widths=[4], scans=["lidar", "memory"])


@pytest.mark.parametrize(("memory", "channels"), [("", 1), ("polar", 2)])
def test_a_convolutional_student_is_a_run_that_loads_and_acts_from_its_scan(tmp_path, memory, channels):
    config = config_for("ClutterNav-v1", {
        **BASE, "scan_memory": memory, "n_envs": 2, "env_workers": 1, "timesteps": 600, "validate_episodes": 1,
        "final_eval_episodes": 0,
        "distill": {"rounds": 2, "round_steps": 256, "warmup_steps": 88, "epochs": 2},
        "ppo": {"net_arch": [16], "scan_conv": [4]}})
    run = start(config, tmp_path / "run")
    train(run, progress=False)
    assert run.read_config().ppo.scan_conv == (4,)
    agent = load(run.root)
    policy = agent.model.policy
    assert isinstance(policy, PrivilegedCriticPolicy) and isinstance(policy.pi_features_extractor, ScanFeatures)
    assert policy.pi_features_extractor.conv[0].in_channels == channels  # a polar memory is the second channel
    env = agent.make_env()
    obs, _ = env.reset(seed=0)
    action, _ = agent.predict(obs)
    assert env.action_space.contains(action)
    env.close()

    def bins(o):
        if memory:
            o, _ = agent._remember(o, True, None)
        tensor, _ = policy.obs_to_tensor(agent._normalizer.normalize_obs(o))
        with th.no_grad():
            return th.cat([d.probs for d in policy.get_distribution(tensor).distribution], dim=1)

    assert not th.allclose(bins(obs), bins(dict(obs, lidar=np.ones_like(obs["lidar"]))))  # the scan reaches it
