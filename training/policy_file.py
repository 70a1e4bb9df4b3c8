"""Load an SB3 ``model.zip`` without unpickling anything in it.

A ``model.zip`` holds the network weights (``policy.pth``, which SB3 reads with ``torch.load(weights_only=True)``)
and a JSON file of the model's attributes. Attributes JSON cannot hold (the policy class, the spaces, schedules,
the last observations of a rollout) are cloudpickled into it, and unpickling them runs whatever code the file's
author put there. SB3's ``custom_objects`` replaces an attribute instead of unpickling it; here every pickled one
is replaced: the policy class, the spaces and the clip range come from the run's config and its env (what the
policy is for anyway), schedules are rebuilt by SB3 from the plain learning rate, and the rest (a rollout's last
observations, episode buffers) is state a loaded model starts afresh.

The weights themselves (``policy.pth``, ``policy.optimizer.pth``, ``pytorch_variables.pth``) are read first with
torch's weights-only loader, member by member, so that one holding a pickle of anything but tensors and plain
values is named (torch's own message suggests loading it without that guard, which would run its code), as is one
holding a NaN or an infinity; every member's size is bounded before it is read.
"""

from __future__ import annotations

import io
import json
import re
import warnings
import zipfile
from pathlib import Path
from typing import Any

import torch
from gymnasium import spaces
from sb3_contrib import RecurrentPPO
from stable_baselines3 import PPO
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from clutter_gym.training.config import TrainConfig

#: bytes a member of a model.zip may hold: the attributes JSON, and each file of weights
MAX_DATA_BYTES, MAX_WEIGHTS_BYTES = 16 << 20, 256 << 20


def read_attributes(path: Path) -> dict[str, Any]:
    """The attributes JSON of ``path`` (an SB3 model.zip) as stored, pickled ones still encoded; every entry of
    the archive is read and checked against its checksum, and every file of weights holds only finite tensors and
    plain values.

    Raises:
        ValueError: ``path`` is not a complete SB3 model file (missing, truncated, corrupt, no weights, a member
            too large, weights that are not plain tensors or not finite), in one line naming the member.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            for info in archive.infolist():
                limit = MAX_DATA_BYTES if info.filename == "data" else MAX_WEIGHTS_BYTES
                if info.file_size > limit:
                    raise ValueError(f"{info.filename} holds {info.file_size:,} bytes, at most {limit:,} allowed")
            broken = archive.testzip()
            if broken is not None:
                raise ValueError(f"{broken} fails its checksum")
            if "policy.pth" not in archive.namelist():
                raise ValueError("it holds no policy.pth")
            for name in archive.namelist():
                if name.endswith(".pth"):
                    _check_weights(name, archive.read(name))
            return json.loads(archive.read("data"))
    except (OSError, zipfile.BadZipFile, KeyError, ValueError, EOFError) as exc:
        raise ValueError(f"{path} is not a complete SB3 model file ({type(exc).__name__}: {exc})") from None


def _check_weights(name: str, content: bytes) -> None:
    """Raise a one-line ``ValueError`` naming the member ``name`` unless torch's weights-only loader reads it and
    every tensor in it is finite."""
    try:
        with warnings.catch_warnings():  # torch warns of pickle protocols it was not written with
            warnings.simplefilter("ignore")
            loaded = torch.load(io.BytesIO(content), map_location="cpu", weights_only=True)
    except Exception as exc:  # UnpicklingError, RuntimeError: torch's many ways of saying "not plain weights"
        text = " ".join(str(exc).split())
        reason = re.search(r"WeightsUnpickler error: (.*?)(?: Check the documentation|$)", text)
        raise ValueError(f"{name} is not plain weights: torch's weights-only loader refused it "
                         f"({(reason.group(1) if reason else text)[:160]}); loading it any other way could run "
                         "code its author put in it") from None
    stack = [loaded]
    while stack:
        item = stack.pop()
        if isinstance(item, torch.Tensor):
            if item.is_floating_point() and not bool(torch.isfinite(item).all()):
                raise ValueError(f"{name} holds a tensor with NaN or infinite values")
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, (list, tuple)):
            stack.extend(item)


def saved_step(path: Path) -> int:
    """The env steps the model in ``path`` was trained for.

    Raises:
        ValueError: ``path`` is not a complete SB3 model file.
    """
    return int(read_attributes(path)["num_timesteps"])


def load_ppo(path: Path, config: TrainConfig, observation_space: spaces.Space, action_space: spaces.Space,
             env: VecEnv | None = None, **distilled: Any) -> OnPolicyAlgorithm:
    """The PPO model in ``path`` for the run of ``config`` (a RecurrentPPO for a recurrent policy), with nothing
    unpickled.

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
        ValueError: ``path`` is not a complete SB3 model file, or its weights do not fit the policy ``config`` and
            the spaces make, in one line.
    """
    from clutter_gym.training.privileged import DistilledPPO, PrivilegedCriticPolicy
    from clutter_gym.training.recurrent_policy import recurrent_policy
    from clutter_gym.training.vec_env import policy_name

    algorithm: type[OnPolicyAlgorithm]
    if config.recurrent:  # a student too: its DAgger rounds need no DistilledPPO (it is not fine-tuned)
        algorithm, distilled = RecurrentPPO, {}
        policy_class = recurrent_policy(isinstance(observation_space, spaces.Dict))
    elif config.teacher.name:
        algorithm, policy_class = DistilledPPO, PrivilegedCriticPolicy
    else:
        algorithm, policy_class = PPO, PPO.policy_aliases[policy_name(observation_space)]
    replacements: dict[str, Any] = {
        "policy_class": policy_class,
        "observation_space": observation_space,
        "action_space": action_space,
        "clip_range": config.ppo.clip_range,
    }
    pickled = [key for key, item in read_attributes(path).items() if isinstance(item, dict) and ":serialized:" in item]
    custom = {key: replacements.get(key) for key in pickled}
    try:
        model = algorithm.load(path, env=env, device="cpu", custom_objects=custom)
    except Exception as exc:  # torch's size mismatches and SB3's checks: many kinds, many lines
        raise ValueError(f"{path} does not fit the policy of this run's config.yaml ({type(exc).__name__}: "
                         f"{' '.join(str(exc).split())[:300]})") from None
    for key, value in distilled.items():
        setattr(model, key, value)
    return model
