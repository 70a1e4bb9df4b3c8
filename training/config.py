"""Training configuration: typed dataclasses, loaded from ``hyperparams/ppo.yml`` and overridden by the user.

The YAML file holds a ``default`` block and one block per env id that overrides it. A user's own file of the
same form (``--hyperparams FILE.yml``) and the command-line options go on top, in that order. Mappings merge key
by key at every depth (``ppo``, ``env_kwargs``, ``env_kwargs.noise``); every other value replaces. Every value is
checked against its field's type and range here, so a typo in a file or on the command line fails before any
env is built, naming the field.
"""

from __future__ import annotations

import itertools
from dataclasses import asdict, dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from clutter_gym.training.distill_config import DistillSettings, TeacherSettings
from clutter_gym.training.env_settings import check_env_kwargs, check_mix, reject_unknown
from clutter_gym.training.ppo_settings import PPOHyperparams, check_range
from clutter_gym.training.residual import MAPLESS_ENVS, PURSUIT_ENVS, check_residual_base, check_residual_space
from clutter_gym.training.scan_memory import MEMORY_KINDS
from clutter_gym.training.teachers import check_teacher
from clutter_gym.util.checks import short_repr
from clutter_gym.util.safe_yaml import read_yaml

HYPERPARAMS_FILE = "ppo.yml"
#: First evaluation seed by default: far from the seeds training starts its envs with (seed, seed + 1, ...).
EVAL_SEED = 1_000_000
#: First seed of the validation episodes run during training to pick the best model; apart from both the
#: training seeds and the evaluation seeds, so the model is chosen on layouts the final evaluation never sees.
VALIDATION_SEED = 2_000_000


@dataclass(frozen=True)
class TrainConfig:
    """Everything a training run depends on; saved as ``config.yaml`` in the run folder.

    Attributes:
        env_id: a registered clutter-gym id.
        seed: seeds PPO and the envs (env i of the vector gets ``seed + i``).
        noise: noise profile name the agent trains under.
        timesteps: total environment steps.
        n_envs: parallel envs.
        env_workers: processes that step the ``n_envs`` envs, each a contiguous block of them: the training
            process itself and ``env_workers - 1`` worker processes (0: one per CPU core, at most ``n_envs``).
            Only speed depends on it, never results.
        checkpoint_every: env steps between checkpoints.
        keep_checkpoints: how many of the newest checkpoints to keep.
        final_eval_episodes: episodes of the evaluation written to ``eval.json`` after training (0: none).
        validate_every: env steps between validations of the current policy (0: none). A validation runs
            ``validate_episodes`` deterministic episodes on held-out layouts; the best policy so far is kept in
            ``best/`` and is the one ``load()``, evaluation and the report use.
        validate_episodes: episodes per validation.
        action_bins: 0: the policy's actions are the env's (continuous); n >= 2: each action entry takes one of n
            values evenly from -1 to 1, picked from a categorical distribution
            (:mod:`clutter_gym.training.binned_actions`: a student that cannot average the teacher's modes).
        scan_memory: "" (none), or what the policy is told of every LIDAR return of the episode, kept by dead
            reckoning: ``"polar"`` or ``"grid"`` (:mod:`clutter_gym.training.scan_memory`; ClutterNav-v1).
        frame_stack: the policy sees its episode's last ``frame_stack`` observations (every entry concatenated,
            oldest first; see :mod:`clutter_gym.training.memory`). 1: the current observation only.
        train_layouts: 0: every training reset samples a new layout; N > 0: the training envs share out N
            fixed layouts (``ceil(N / n_envs)`` each; see :mod:`clutter_gym.training.layout_pool`), so per-layout
            work such as the ClutterReach subgoal's plan is done once. Validation and evaluation are unaffected.
        train_env_mix: a training device: ``{argument: [v0, v1, ...]}`` gives the training envs the listed
            values of each ``gym.make`` argument on top of ``env_kwargs`` (for instance
            ``{obstacle_density: [0.05, 0.12, 0.2]}`` trains over three clutter levels; ``noise`` takes profile
            names, with the run's noise-section overrides on each). With several arguments, env ``i`` takes the
            ``i mod n``-th of their ``n`` combinations, so that no value is tied to another. Validation,
            evaluation and ``load()`` use ``env_kwargs`` and ``noise`` alone.
        residual_gain: 0: the policy's action is the env's; g > 0: the env's action is
            ``clip(pursuit(obs) + policy action, -1, 1)``, a residual policy on a base controller with gain g
            (ClutterNav-v1's potential field on the goal, or ClutterReach-v1's and ClutterFly-v1's pursuit of the
            subgoal with ``subgoal_lookahead > 0``; the pursuits and what their gain means:
            :mod:`clutter_gym.training.residual`).
        residual_space: what a residual policy's action adds to: ``"action"``, the base controller's action;
            ``"velocity"`` (ClutterFly-v1), the velocity its flyer commands, the policy's action then being a
            (3,) velocity offset in units of the flyer's top speed; ``"waypoint"``, where the base controller goes
            (ClutterNav-v1's and ClutterFly-v1's direction, ClutterReach-v1's hand displacement and pitch)
            (:func:`clutter_gym.training.residual.residual_map`).
        residual_base: gains of the base controller other than its defaults, ClutterFly-v1's flyer only
            (``{attitude_gain: 4.0}``; the names: :data:`clutter_gym.training.residual.FLYER_GAINS`).
        env_kwargs: extra ``gym.make`` keyword arguments. Its ``noise`` entry, if any, holds noise-section
            overrides (``{"lidar": {"range_sigma": 0.02}}``) applied on top of whichever profile the env is
            made under, for training and evaluation alike. A distilled student's are its own: what its policy reads.
        teacher: the privileged teacher a student is distilled from (:mod:`clutter_gym.training.distill_config`);
            none by default (PPO from scratch).
        distill: the DAgger rounds before PPO, and the fine-tuning's pull towards the teacher (with a teacher).
        critic_inputs: observation entries of the teacher's env that PPO's critic reads and its actor does not
            (an asymmetric actor-critic; with a teacher). Training steps count the distillation's: PPO fine-tunes
            from there up to ``timesteps``.
        ppo: PPO hyperparameters.
    """

    env_id: str = "ClutterNav-v1"
    seed: int = 0
    noise: str = "none"
    timesteps: int = 500_000
    n_envs: int = 4
    env_workers: int = 0
    checkpoint_every: int = 50_000
    keep_checkpoints: int = 3
    final_eval_episodes: int = 20
    validate_every: int = 0
    validate_episodes: int = 20
    action_bins: int = 0
    scan_memory: str = ""
    frame_stack: int = 1
    train_layouts: int = 0
    residual_gain: float = 0.0
    residual_space: str = "action"
    residual_base: dict[str, float] = field(default_factory=dict)
    train_env_mix: dict[str, list[Any]] = field(default_factory=dict)
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    teacher: TeacherSettings = field(default_factory=TeacherSettings)
    distill: DistillSettings = field(default_factory=DistillSettings)
    critic_inputs: tuple[str, ...] = ()
    ppo: PPOHyperparams = field(default_factory=PPOHyperparams)

    def __post_init__(self) -> None:
        from clutter_gym import ENV_IDS
        from clutter_gym.noise.profiles import PROFILE_NAMES

        if self.env_id not in ENV_IDS:
            raise ValueError(f"env_id must be one of {ENV_IDS}, got {short_repr(self.env_id)}")
        if self.noise not in PROFILE_NAMES:
            raise ValueError(f"noise must be one of {PROFILE_NAMES}, got {short_repr(self.noise)}")
        check_range("seed", self.seed, 0, 2**31 - 1)
        check_range("timesteps", self.timesteps, 1, 10**10)
        check_range("n_envs", self.n_envs, 1, 256)
        check_range("env_workers", self.env_workers, 0, self.n_envs)
        check_range("checkpoint_every", self.checkpoint_every, 1, 10**10)
        check_range("keep_checkpoints", self.keep_checkpoints, 1, 1000)
        check_range("final_eval_episodes", self.final_eval_episodes, 0, 100_000)
        check_range("validate_every", self.validate_every, 0, 10**10)
        check_range("validate_episodes", self.validate_episodes, 1, 100_000)
        check_range("frame_stack", self.frame_stack, 1, 32)
        if self.action_bins and not 2 <= self.action_bins <= 101 or isinstance(self.action_bins, bool):
            raise ValueError(f"action_bins must be 0 (continuous actions) or an integer in [2, 101], got "
                             f"{short_repr(self.action_bins)}")
        if self.scan_memory not in ("", *MEMORY_KINDS):
            raise ValueError(f"scan_memory must be one of {MEMORY_KINDS} or empty (none), got {self.scan_memory!r}")
        check_range("train_layouts", self.train_layouts, 0, 10**7)
        check_range("residual_gain", self.residual_gain, 0.0, 1000.0)
        self.teacher.check(self.env_id)
        if self.teacher.name and self.env_kwargs.get("subgoal_lookahead"):
            raise ValueError("env_kwargs.subgoal_lookahead must be 0 for a student distilled from a teacher: its "
                             "policy reads no planner subgoal (the teacher's comes with teacher.env_kwargs), got "
                             f"{short_repr(self.env_kwargs['subgoal_lookahead'])}")
        if self.critic_inputs and not self.teacher.name:
            raise ValueError("critic_inputs needs a teacher (its env gives the privileged entries)")
        if not all(isinstance(key, str) for key in self.critic_inputs):
            raise ValueError(f"critic_inputs must be a list of observation entry names, got {list(self.critic_inputs)}")
        if self.teacher.name and self.residual_gain:
            raise ValueError("a student distilled from a teacher acts on its own (residual_gain 0); ClutterFly-v1's "
                             "acts through the flight controller with residual_space: velocity")
        if self.residual_gain and not (self.env_id in MAPLESS_ENVS
                                       or self.env_id in PURSUIT_ENVS and self.env_kwargs.get("subgoal_lookahead")):
            raise ValueError(f"residual_gain > 0 needs env_id in {MAPLESS_ENVS}, or in {PURSUIT_ENVS} with "
                             "env_kwargs.subgoal_lookahead > 0")
        reach_field = self.env_id == "ClutterReach-v1" and not self.env_kwargs.get("subgoal_lookahead")
        if self.residual_gain and reach_field and not (self.env_kwargs.get("observe_directions")
                                                       and self.env_kwargs.get("control", "joint_velocity")
                                                       == "joint_velocity"):
            raise ValueError("residual_gain > 0 on ClutterReach-v1 without a subgoal (a residual on the proximity "
                             "field) needs env_kwargs.observe_directions: true and control: joint_velocity")
        check_residual_space(self.env_id, self.residual_space)
        if self.teacher.name:
            check_teacher(self.env_id, self.teacher.name, self.residual_space)
        if (self.env_id == "ClutterReach-v1" and self.residual_space == "waypoint"
                and self.env_kwargs.get("control", "joint_velocity") != "joint_velocity"):
            raise ValueError("residual_space waypoint on ClutterReach-v1 drives the joints: it needs "
                             "env_kwargs.control: joint_velocity")
        if self.residual_space != "action" and not (self.residual_gain or self.teacher.name):
            raise ValueError(f"residual_space {self.residual_space!r} needs residual_gain > 0, or a teacher (the "
                             "student then commands the velocity itself)")
        check_residual_base(self.env_id, self.residual_base)
        if self.residual_base and not self.residual_gain:
            raise ValueError("residual_base needs residual_gain > 0 (it sets the gains of a residual's base)")
        check_env_kwargs(self.env_id, self.noise, self.env_kwargs)
        check_mix(self.env_id, self.train_env_mix)
        if self.ppo.lstm_hidden_size:
            self._check_recurrent()
        if self.ppo.scan_conv and (not self.teacher.name or self.recurrent or self.frame_stack > 1):
            raise ValueError("ppo.scan_conv is a distilled student's (it needs a teacher, ppo.lstm_hidden_size 0 and "
                             f"frame_stack 1), got teacher {self.teacher.name!r}, lstm_hidden_size "
                             f"{self.ppo.lstm_hidden_size}, frame_stack {self.frame_stack}")
        if self.ppo.batch_size > self.ppo.n_steps * self.n_envs:
            raise ValueError(f"ppo.batch_size must be in [2, n_steps * n_envs = {self.ppo.n_steps * self.n_envs}], "
                             f"got {self.ppo.batch_size}")

    def _check_recurrent(self) -> None:
        """A recurrent policy's limits: its LSTM is its memory (no frame stack), its critic reads what its actor
        reads, and a distilled recurrent student is not fine-tuned with PPO."""
        if self.frame_stack > 1:
            raise ValueError(f"frame_stack must be 1 with ppo.lstm_hidden_size > 0 (the LSTM is the policy's memory), "
                             f"got {self.frame_stack}")
        if self.critic_inputs:
            raise ValueError("critic_inputs needs ppo.lstm_hidden_size 0: the privileged critic is an MLP policy's")
        if self.teacher.name and self.timesteps > self.distill.steps:
            raise ValueError(f"timesteps must be at most the distillation's {self.distill.steps} steps (warmup_steps + "
                             f"rounds x round_steps) for a recurrent student: PPO fine-tuning after DAgger is "
                             f"built for memoryless students only, got {self.timesteps}")

    @property
    def recurrent(self) -> bool:
        """The policy is recurrent (``ppo.lstm_hidden_size`` > 0)."""
        return self.ppo.lstm_hidden_size > 0

    def train_kwargs(self, index: int) -> dict[str, Any]:
        """``gym.make`` keyword arguments of training env ``index``: :meth:`make_kwargs` with its share of
        ``train_env_mix``."""
        combinations = list(itertools.product(*self.train_env_mix.values()))
        mixed = dict(zip(self.train_env_mix, combinations[index % len(combinations)]))
        return {**self.make_kwargs(noise=mixed.pop("noise", None)), **mixed}

    @property
    def layouts_per_env(self) -> int:
        """Each training env's share of ``train_layouts`` (0: a new layout every reset)."""
        return -(-self.train_layouts // self.n_envs)

    def make_kwargs(self, noise: str | None = None) -> dict[str, Any]:
        """``gym.make`` keyword arguments for the run's env under profile ``noise`` (default: the training one)."""
        kwargs = dict(self.env_kwargs)
        sections = kwargs.pop("noise", None)
        profile = self.noise if noise is None else noise
        kwargs["noise"] = {"profile": profile, **sections} if sections else profile
        return kwargs

    def teacher_kwargs(self, noise: str | None = None) -> dict[str, Any]:
        """``gym.make`` keyword arguments of the env the teacher labels: :meth:`make_kwargs` and the teacher's own."""
        return {**self.make_kwargs(noise), **self.teacher.kwargs(self.env_id)}

    @property
    def uses_base(self) -> bool:
        """The policy acts through a base controller: a residual on it, or (a student on ClutterFly-v1) the
        flight controller flying the velocity the policy commands."""
        return bool(self.residual_gain) or self.residual_space != "action"

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["ppo"]["net_arch"] = list(self.ppo.net_arch)
        data["ppo"]["scan_conv"] = list(self.ppo.scan_conv)
        data["critic_inputs"] = list(self.critic_inputs)
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """Build from a plain mapping (a YAML block or a saved ``config.yaml``); unknown keys are errors."""
        data = dict(data)
        reject_unknown("config key(s)", data, {f.name for f in fields(cls)})
        ppo = dict(data.pop("ppo", {}) or {})
        reject_unknown("ppo key(s)", ppo, {f.name for f in fields(PPOHyperparams)})
        for key in ("net_arch", "scan_conv"):
            if key in ppo:
                ppo[key] = tuple(ppo[key] or ())
        data["env_kwargs"] = dict(data.get("env_kwargs") or {})
        if data.get("residual_base") is None:  # an empty YAML block reads as None
            data.pop("residual_base", None)
        teacher = data.pop("teacher", None) or {}
        if not isinstance(teacher, dict):
            raise ValueError(f"teacher must be a mapping (name, env_kwargs), got {teacher!r}")
        reject_unknown("teacher key(s)", teacher, {"name", "env_kwargs"})
        data["teacher"] = TeacherSettings(**teacher)
        data["distill"] = DistillSettings.from_dict(data.pop("distill", None) or {})
        data["critic_inputs"] = tuple(data.pop("critic_inputs", None) or ())
        return cls(**data, ppo=PPOHyperparams(**ppo))


def deep_merge(base: dict[str, Any], top: dict[str, Any]) -> dict[str, Any]:
    """``base`` updated by ``top``: mappings merge key by key at every depth, other values replace."""
    merged = dict(base)
    for key, value in top.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def hyperparams_table() -> dict[str, Any]:
    """The parsed ``hyperparams/ppo.yml`` shipped with the package."""
    text = resources.files("clutter_gym.training").joinpath("hyperparams", HYPERPARAMS_FILE).read_text()
    return yaml.safe_load(text)


def shipped_hyperparams() -> list[str]:
    """Names of the hyperparameter files shipped beside ``ppo.yml`` (such as ``sensors``), for
    ``--hyperparams NAME``."""
    folder = resources.files("clutter_gym.training").joinpath("hyperparams")
    return sorted(f.name[:-4] for f in folder.iterdir() if f.name.endswith(".yml") and f.name != HYPERPARAMS_FILE)


def read_hyperparams_file(path: str | Path) -> dict[str, Any]:
    """A user's hyperparameter file, or a shipped one by name: the shipped file's form (``default`` and env-id
    blocks), checked by name.

    Raises:
        FileNotFoundError: no such file, and not a shipped name (the message lists those).
        ValueError: not YAML, not a mapping of blocks, or a block named neither ``default`` nor an env id.
    """
    from clutter_gym import ENV_IDS

    name = str(path)
    if name in shipped_hyperparams() and not Path(name).is_file():
        path = Path(str(resources.files("clutter_gym.training").joinpath("hyperparams", f"{name}.yml")))
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"hyperparameter file {name!r} does not exist (nor is it a shipped name: "
                                f"{', '.join(shipped_hyperparams())})")
    table = read_yaml(path, f"hyperparameter file {str(path)!r}")
    if table is None:
        return {}
    if not isinstance(table, dict) or not all(isinstance(block, dict | None) for block in table.values()):
        raise ValueError(f"hyperparameter file {str(path)!r} must map 'default' and env ids to blocks of settings "
                         "(the form of clutter_gym/training/hyperparams/ppo.yml)")
    reject_unknown(f"block name(s) in {str(path)!r}", table, {"default", *ENV_IDS})
    return table


def user_settings(table: dict[str, Any], env_id: str) -> dict[str, Any]:
    """A user table's settings for ``env_id``: its ``default`` block with the env's block on top."""
    return deep_merge(table.get("default") or {}, table.get(env_id) or {})


def config_for(env_id: str, overrides: dict[str, Any] | None = None) -> TrainConfig:
    """The shipped ``default`` block, then the env's block, then ``overrides`` (a user's file, then options)."""
    table = hyperparams_table()
    merged = deep_merge({"env_id": env_id}, user_settings(table, env_id))
    return TrainConfig.from_dict(deep_merge(merged, overrides or {}))
