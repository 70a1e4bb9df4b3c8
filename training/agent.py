"""A trained run, ready to act: ``agent = clutter_gym.training.load(run_dir)``.

```python
from clutter_gym.training import load

agent = load("out/main/run")
env = agent.make_env()                      # the env the run trained on; agent.make_env(noise="harsh") for another
obs, info = env.reset(seed=0)
state, done = None, False                   # None: the start of an episode
while not done:
    action, state = agent.predict(obs, state)
    obs, reward, terminated, truncated, info = env.step(action)
    done = terminated or truncated
```

The run folder's ``config.yaml`` is the recipe: env id, env arguments, noise profile and the PPO settings, which
say which observation processing the policy was trained behind (normalisation, and a frame stack whose frames
the agent keeps in ``state``, as it keeps a recurrent policy's LSTM state) and whether its actions are residuals on
a base controller (:mod:`clutter_gym.training.residual`), which ``predict`` then adds. The model folder holds SB3's
``model.zip`` and, when observations were normalised, the ``VecNormalize`` statistics (``vecnormalize.npz``);
loading either runs no code from the files.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env.stacked_observations import StackedObservations

from clutter_gym.training.binned_actions import binned_space, decode
from clutter_gym.training.config import TrainConfig, deep_merge
from clutter_gym.training.memory import frame_space, push_frame
from clutter_gym.training.normalizer import NORMALIZER_FILE, detached, normalizer_path
from clutter_gym.training.policy_file import load_ppo
from clutter_gym.training.pretrained import resolve_run
from clutter_gym.training.residual import policy_action_space, residual_map, subgoal_pursuit
from clutter_gym.training.run_dir import MODEL_FILE, IncompatibleRunError, RunDir
from clutter_gym.training.scan_memory import ScanMemory, memory_for

if TYPE_CHECKING:
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm


class Agent:
    """A run's policy behind the observation processing it was trained with; acts on plain env observations.

    Attributes:
        run: the run folder.
        config: the run's settings (env id, env arguments, training noise profile, PPO settings).
        model: the stable-baselines3 PPO model (sb3-contrib's RecurrentPPO for a recurrent policy).
        folder: the model folder that was loaded (``model/``, or a checkpoint's; None for a model in training).
        step: env steps the model was trained for.
        observation_space: the space of one env observation (the policy's own is a stack of them with
            ``config.frame_stack`` above 1).
    """

    def __init__(self, run: RunDir, config: TrainConfig, model: OnPolicyAlgorithm, normalizer: Any | None,
                 folder: Path | None) -> None:
        self.run, self.config, self.model, self.folder = run, config, model, folder
        self.step = int(model.num_timesteps)
        # a student with a privileged critic acts on the student's entries alone
        self._policy_space = frame_space(getattr(model.policy, "actor_space", model.observation_space),
                                         config.frame_stack)
        self.observation_space = self._policy_space
        self._memory = _memory(config) if config.scan_memory else None
        if self._memory is not None:  # the agent keeps the memory entry itself, from the observations
            self.observation_space = spaces.Dict({k: v for k, v in self._policy_space.spaces.items() if k != "memory"})
        self._normalizer = _for_entries(normalizer, self._policy_space)
        self._residual = _residual(config) if config.uses_base else None

    def predict(self, obs: dict[str, np.ndarray] | np.ndarray, state: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        """The action for one observation of the run's env (or a batch of them, one per row).

        Args:
            obs: an observation as the env returns it.
            state: the agent's memory; None at the start of an episode, then what the previous call returned.
                It holds the frame stack of a run trained with ``frame_stack`` above 1, the LSTM's state of a
                recurrent policy (``ppo.lstm_hidden_size``) and the LIDAR's memory of a run trained with a
                ``scan_memory`` (for a batch, one per row; the rows start their episodes together), and is None
                for a memoryless policy.
            deterministic: the mean action (True) or a sample from the policy's distribution.

        Returns:
            ``(action, state)``, as SB3's ``predict``.
        """
        single = self._check_obs(obs)
        raw = obs
        if self._memory is not None:
            obs, memories = self._remember(obs, single, None if state is None else state[0])
            state = None if state is None else state[1]
        if self._normalizer is not None:
            obs = self._normalizer.normalize_obs(obs)
        if self.config.frame_stack > 1:
            batch = _as_batch(obs) if single else obs
            stacked, state = push_frame(batch, state, self.config.frame_stack, self._policy_space)
            action, _ = self.model.predict(stacked, deterministic=deterministic)
            action = action[0] if single else action
        elif self.config.recurrent:  # the LSTM's (hidden, cell) state; zeros at an episode's start
            rows = 1 if single else len(next(iter(obs.values())) if isinstance(obs, dict) else obs)
            action, state = self.model.predict(obs, state, episode_start=np.full(rows, state is None),
                                               deterministic=deterministic)
        else:
            action, _ = self.model.predict(obs, deterministic=deterministic)
        if self.config.action_bins:
            action = decode(action, self.config.action_bins)
        if self._residual is not None:
            action = self._residual(raw, action)
        if self._memory is not None:
            state = (memories, state)
        return action, state

    def _remember(self, obs: dict[str, np.ndarray], single: bool, memories: list | None) -> tuple[dict, list]:
        """``obs`` with its ``memory`` entry, each row's memory moved on by its observation (new ones at an
        episode's start)."""
        rows = [obs] if single else [{k: v[i] for k, v in obs.items()} for i in range(len(obs["lidar"]))]
        start = memories is None
        if start:
            memories = [copy.deepcopy(self._memory) for _ in rows]
        entries = [m.update(row["lidar"], None if start else row["velocity"]) for m, row in zip(memories, rows)]
        return {**obs, "memory": entries[0] if single else np.stack(entries)}, memories

    def make_env(self, noise: str | dict[str, Any] | None = None, render_mode: str | None = None,
                 **overrides: Any) -> gym.Env:
        """The run's env: its env arguments under ``noise`` (default: the training profile), with ``overrides``.

        Args:
            noise: a profile name, or a mapping as ``gym.make`` takes it (``{"profile": "harsh", "lidar":
                {"range_sigma": 0.05}}``). The run's own noise-section overrides apply underneath, as in training.
            render_mode: passed to ``gym.make``.
            **overrides: env arguments on top of the run's.

        Raises:
            ValueError: an unknown profile or env argument (named, with the allowed ones), or settings that
                change the observation or action shapes the policy was trained on.
        """
        sections = {"profile": noise} if isinstance(noise, str) else dict(noise or {})
        profile = sections.pop("profile", self.config.noise)
        if sections:
            overrides = {**overrides, "noise": sections}
        data = deep_merge(self.config.to_dict(), {"noise": profile, "env_kwargs": overrides})
        config = TrainConfig.from_dict(data)
        env = gym.make(config.env_id, render_mode=render_mode, **config.make_kwargs())
        try:
            for what, trained, built in (("observation", self.observation_space, env.observation_space),
                                         ("action", self.model.action_space,
                                          policy_action_space(env.action_space, self.config.residual_space,
                                                              self.config.env_id))):
                if _shapes(trained) != _shapes(built):
                    raise ValueError(f"these settings give {what}s of shape {_shapes(built)}; the policy of "
                                     f"{self.run.root} was trained on {_shapes(trained)}")
        except BaseException:
            env.close()
            raise
        return env

    def _check_obs(self, obs: Any) -> bool:
        """Raises a named error for an observation the policy cannot take; True for one observation, False for a
        batch."""
        expected = self.observation_space
        if isinstance(expected, spaces.Dict):
            if not isinstance(obs, dict) or set(obs) != set(expected.spaces):
                keys = sorted(obs) if isinstance(obs, dict) else type(obs).__name__
                raise ValueError(f"obs must be a dict with keys {sorted(expected.spaces)}, got {keys}")
            singles = [_check_shape(f"obs[{key!r}]", np.shape(obs[key]), space.shape)
                       for key, space in expected.spaces.items()]
            if len(set(singles)) > 1:
                raise ValueError("obs entries must all be single observations or all batches of the same size")
            return singles[0]
        return _check_shape("obs", np.shape(obs), expected.shape)


def _for_entries(normalizer: Any | None, space: spaces.Space) -> Any | None:
    """The observation normalisation of ``normalizer`` for observations of ``space`` (a student's entries, where
    the statistics also hold its critic's); None without one."""
    if normalizer is None or not normalizer.norm_obs:
        return None
    if not isinstance(space, spaces.Dict) or not isinstance(normalizer.obs_rms, dict):
        return normalizer
    if set(normalizer.obs_rms) <= set(space.spaces):
        return normalizer
    narrowed = object.__new__(type(normalizer))  # a shallow copy: the training run's own normaliser stays as it is
    narrowed.__dict__.update(normalizer.__dict__)
    narrowed.norm_obs_keys = [key for key in normalizer.norm_obs_keys if key in space.spaces]
    narrowed.obs_rms = {key: normalizer.obs_rms[key] for key in narrowed.norm_obs_keys}
    return narrowed


def _memory(config: TrainConfig) -> ScanMemory:
    """An empty LIDAR memory of the run's kind, for the LIDAR of the env its settings make."""
    env = gym.make(config.env_id, **config.make_kwargs())
    try:
        return memory_for(env, config.scan_memory)
    finally:
        env.close()


def _residual(config: TrainConfig):
    """The run's residual on its base controller; ClutterNav's and mapless ClutterReach's are built on an env made
    with the run's settings (they read its LIDAR or its proximity readings)."""
    mapless = not config.env_kwargs.get("subgoal_lookahead")
    reads_env = (config.env_id == "ClutterNav-v1" or mapless and config.env_id == "ClutterReach-v1"
                 or config.residual_space == "waypoint")
    env = gym.make(config.env_id, **config.make_kwargs()) if reads_env else None
    try:
        pursuit = subgoal_pursuit(config.env_id, config.residual_gain, env, mapless, config.residual_space,
                                  config.residual_base)
    finally:
        if env is not None:
            env.close()
    return residual_map(pursuit, config.residual_space)


def _as_batch(obs: dict[str, np.ndarray] | np.ndarray) -> dict[str, np.ndarray] | np.ndarray:
    """One observation as a batch of one."""
    if isinstance(obs, dict):
        return {key: np.asarray(value)[None] for key, value in obs.items()}
    return np.asarray(obs)[None]


def _shapes(space: spaces.Space) -> Any:
    if isinstance(space, spaces.Dict):
        return {key: sub.shape for key, sub in space.spaces.items()}
    return space.shape


def _check_shape(name: str, shape: tuple[int, ...], expected: tuple[int, ...]) -> bool:
    """True for one observation of the expected shape, False for a batch of them; else a named error."""
    if shape == expected:
        return True
    if shape[1:] != expected:
        raise ValueError(f"{name} must have shape {expected} (or (n, {', '.join(map(str, expected))}) for a "
                         f"batch), got {shape}")
    return False


def load(run_dir: str | Path, step: int | None = None, trust_pickle: bool = False) -> Agent:
    """Load a trained run as an :class:`Agent`, unpickling nothing (docs/training.md, "Loading runs from others").

    Args:
        run_dir: a run folder written by ``clutter-gym train`` (or by the main job: ``out/main/run``), or
            ``pretrained/NAME``, an agent shipped with the package (:mod:`clutter_gym.training.pretrained`).
        step: load the checkpoint of this step; None loads the final model, or the newest checkpoint of a
            run that has not finished.
        trust_pickle: read the normalisation statistics of a run written by clutter-gym 0.1, which kept them in
            a pickle (``vecnormalize.pkl``); a pickle can run any code its author put in it.

    Raises:
        FileNotFoundError: no run, model or checkpoint there (the message lists the checkpoints there are), no
            shipped agent of that name, or the normalisation statistics of a run trained with ``normalize_obs`` are
            missing.
        UntrustedFileError: the statistics are in a pickle and ``trust_pickle`` is False.
        ValueError: the statistics are not what the run's config and its env's observations make (the message
            names the file and the setting or statistic: :mod:`clutter_gym.training.statistics_file`).
        IncompatibleRunError: a run this version of clutter-gym cannot rebuild; the message names the
            version that wrote it.
    """
    run = RunDir(resolve_run(run_dir))
    config = run.read_config()
    if step is None:
        folder = run.policy_folder()
    else:
        found = dict(run.checkpoints())
        if step not in found:
            raise FileNotFoundError(f"{run.root} has no checkpoint of step {step}; it has {sorted(found)}")
        folder = found[step]
    statistics = normalizer_path(folder, trust_pickle)
    if statistics is None and config.ppo.normalize_obs:
        raise FileNotFoundError(f"{folder / NORMALIZER_FILE} is missing: {run.root} was trained on normalised "
                                "observations, and its policy acts wrongly on raw ones")
    env_observation_space, action_space = env_spaces(config)
    normalizer = None if statistics is None else detached(statistics, config, env_observation_space, action_space)
    try:
        model = load_ppo(folder / MODEL_FILE, config, stacked_space(env_observation_space, config.frame_stack),
                         action_space)
    except Exception as exc:  # zip, torch and SB3 raise many kinds; all mean "cannot rebuild this model here"
        versions = run.written_by()
        raise IncompatibleRunError(f"{folder} cannot be loaded ({type(exc).__name__}: {exc}); it was written by "
                                   f"clutter-gym {versions.get('clutter-gym', '0.1.0 or older')} "
                                   f"({versions or 'versions not recorded'})") from None
    return Agent(run, config, model, normalizer, folder)


def env_spaces(config: TrainConfig) -> tuple[spaces.Space, spaces.Space]:
    """The space of one observation as the run's policy takes it, and its action space: the entries of the env the
    run's config makes, with the LIDAR's ``memory`` of a run that keeps one and the critic's entries of a run with
    ``critic_inputs`` (from the teacher's env as made: it is never reset here), and the bins of binned actions."""
    env = gym.make(config.env_id, **config.make_kwargs())
    try:
        observation_space = env.observation_space
        action_space = policy_action_space(env.action_space, config.residual_space, config.env_id)
    finally:
        env.close()
    if config.action_bins:
        action_space = binned_space(action_space, config.action_bins)
    extra: dict[str, spaces.Space] = {}
    if config.scan_memory:
        extra["memory"] = spaces.Box(0.0, 1.0, (_memory(config).size,), np.float32)
    if config.critic_inputs:
        teacher_env = gym.make(config.env_id, **config.teacher_kwargs())
        extra.update({key: teacher_env.observation_space[key] for key in config.critic_inputs})
        teacher_env.close()
    if extra:
        observation_space = spaces.Dict({**observation_space.spaces, **extra})
    return observation_space, action_space


def stacked_space(space: spaces.Space, frame_stack: int) -> spaces.Space:
    """The space of a stack of ``frame_stack`` observations of ``space``, which the policy takes."""
    return StackedObservations(1, frame_stack, space).stacked_observation_space if frame_stack > 1 else space
