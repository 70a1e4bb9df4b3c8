"""Load an SB3 ``model.zip`` without unpickling anything in it.

A ``model.zip`` holds the network weights (``policy.pth``, which SB3 reads with ``torch.load(weights_only=True)``)
and a JSON file of the model's attributes. Attributes JSON cannot hold (the policy class, the spaces, schedules,
the last observations of a rollout) are cloudpickled into it, and unpickling them runs whatever code the file's
author put there. SB3's ``custom_objects`` replaces an attribute instead of unpickling it; here every pickled one
is replaced: the policy class, the spaces and the clip range come from the run's config and its env (what the
policy is for anyway), schedules are rebuilt by SB3 from the plain learning rate, and the rest (a rollout's last
observations, episode buffers) is state a loaded model starts afresh.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecEnv

from clutter_gym.training.config import TrainConfig


def read_attributes(path: Path) -> dict[str, Any]:
    """The attributes JSON of ``path`` (an SB3 model.zip) as stored, pickled ones still encoded; every entry of
    the archive is read and checked against its checksum.

    Raises:
        ValueError: ``path`` is not a complete SB3 model file (missing, truncated, corrupt, no weights).
    """
    try:
        with zipfile.ZipFile(path) as archive:
            broken = archive.testzip()
            if broken is not None:
                raise ValueError(f"{broken} fails its checksum")
            if "policy.pth" not in archive.namelist():
                raise ValueError("it holds no policy.pth")
            return json.loads(archive.read("data"))
    except (OSError, zipfile.BadZipFile, KeyError, ValueError, EOFError) as exc:
        raise ValueError(f"{path} is not a complete SB3 model file ({type(exc).__name__}: {exc})") from None


def saved_step(path: Path) -> int:
    """The env steps the model in ``path`` was trained for.

    Raises:
        ValueError: ``path`` is not a complete SB3 model file.
    """
    return int(read_attributes(path)["num_timesteps"])


def load_ppo(path: Path, config: TrainConfig, observation_space: spaces.Space, action_space: spaces.Space,
             env: VecEnv | None = None, **distilled: Any) -> PPO:
    """The PPO model in ``path`` for the run of ``config``, with nothing unpickled.

    Args:
        path: the model.zip.
        config: the run's settings (the clip range; a teacher's run is a
            :class:`~clutter_gym.training.privileged.DistilledPPO` whose policy may have a privileged critic).
        observation_space: the policy's observation space (a frame stack's, if the run stacks frames; with
            ``critic_inputs``, the critic's entries too).
        action_space: the env's action space.
        env: the vector env to continue training on (None: a model to act with).
        **distilled: a teacher's run's :class:`DistilledPPO` arguments that are not saved (its label recorder).

    Raises:
        ValueError: ``path`` is not a complete SB3 model file.
    """
    from clutter_gym.training.privileged import DistilledPPO, PrivilegedCriticPolicy
    from clutter_gym.training.vec_env import policy_name

    policy_class = PrivilegedCriticPolicy if config.teacher.name else PPO.policy_aliases[policy_name(observation_space)]
    replacements: dict[str, Any] = {
        "policy_class": policy_class,
        "observation_space": observation_space,
        "action_space": action_space,
        "clip_range": config.ppo.clip_range,
    }
    pickled = [key for key, item in read_attributes(path).items() if isinstance(item, dict) and ":serialized:" in item]
    custom = {key: replacements.get(key) for key in pickled}
    algorithm = DistilledPPO if config.teacher.name else PPO
    model = algorithm.load(path, env=env, device="cpu", custom_objects=custom)
    for key, value in distilled.items():
        setattr(model, key, value)
    return model
