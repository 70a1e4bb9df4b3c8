"""Which student fits its teacher best, and generalises: memory, or a convolution over the scan? Offline, on
teacher-driven data.

The teacher of the env's shipped ``sensors`` block drives its 16 training envs (after a warm-up that fits the
observation normalisation, then frozen, as the distillation does) and labels every state; the first ``--fit``
vector steps are fitted on and the next ``--held-out`` held out. Each student is the shipped block's (its net, its
bins, its distillation settings) with the variant's changes, and reports its imitation loss on the data it was fitted
on and on the held-out episodes: a student that fits well and generalises badly memorised episodes.

    python -m benchmarks.learning.offline_memory --env ClutterFly-v1

Variants: ``mlp`` (the shipped memoryless student), ``conv-W-W..`` (the same with its LIDAR read by convolution
layers of widths W, ``ppo.scan_conv``; :mod:`clutter_gym.training.scan_features`), ``between-E-L`` (sb3-contrib's
recurrent policy, the LSTM between the features and the hidden layers, E epochs, sequences of L steps, 8 a batch),
``beside-E-L`` (the project's recurrent policy, the hidden layers reading the features beside the LSTM;
:mod:`clutter_gym.training.recurrent_policy`).
Sequences are of one episode each, cut at L steps (later pieces start from zeros here: the data is the teacher's
and no student held a state while collecting it).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
import torch as th
from sb3_contrib import RecurrentPPO

import clutter_gym  # noqa: F401  (registers the envs)
from clutter_gym.training.config import TrainConfig, config_for, deep_merge, read_hyperparams_file, user_settings
from clutter_gym.training.distill import Dataset, _normalizer, fit
from clutter_gym.training.privileged import distribution_loss, imitation_loss
from clutter_gym.training.sequences import SequenceDataset, fit_sequences
from clutter_gym.training.train import build_model
from clutter_gym.training.vec_env import training_env

SEQUENCES_PER_BATCH = 8
Step = tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]  # observations, labels, episode starts


def shipped(env_id: str, **changes: object) -> TrainConfig:
    """The env's shipped ``sensors`` block with ``changes`` on top, its envs stepped in this process."""
    block = user_settings(read_hyperparams_file("sensors"), env_id)
    return config_for(env_id, deep_merge(block, {"env_workers": 1, **changes}))


def collect(config: TrainConfig, steps: int, warmup: int = 256) -> list[Step]:
    """``steps`` vector steps driven by the teacher, after ``warmup`` that fit the normalisation."""
    venv = training_env(config, seed=config.seed)
    venv.env_method("set_teacher_share", 1.0)
    obs, starts, out = venv.reset(), np.ones(config.n_envs, bool), []
    idle = np.zeros((config.n_envs, *venv.action_space.shape), venv.action_space.dtype)  # the teacher drives
    try:
        for i in range(warmup + steps):
            if i == warmup:
                _normalizer(venv).training = False
            new, _, dones, infos = venv.step(idle)
            if i >= warmup:
                out.append(({k: v.copy() for k, v in obs.items()}, np.stack([f["teacher_action"] for f in infos]),
                            starts))
            obs, starts = new, dones
    finally:
        venv.close()
    return out


def memoryless(config: TrainConfig, fit_on: list[Step], held: list[Step]) -> tuple[float, float]:
    """The shipped student's fit loss and held-out loss."""
    venv = training_env(config, seed=config.seed)
    model = build_model(config, venv)
    venv.close()
    data = Dataset(10**8)
    for obs, labels, _ in fit_on:
        data.add(obs, labels)
    settings, bins = config.distill, config.action_bins
    loss = fit(model, data, settings, th.optim.Adam(model.policy.parameters(), lr=settings.learning_rate), bins)
    obs = {k: th.as_tensor(np.concatenate([o[k] for o, _, _ in held])) for k in held[0][0]}
    labels = th.as_tensor(np.concatenate([label for _, label, _ in held]))
    with th.no_grad():
        return loss, float(imitation_loss(model.policy, obs, labels, bins))


def sequences(steps: list[Step], length: int, hidden: int) -> SequenceDataset:
    data = SequenceDataset(10**8, length, hidden)
    for obs, labels, starts in steps:
        data.add(obs, labels, np.ones(len(labels)), starts, None)
    return data


def recurrent(config: TrainConfig, fit_on: list[Step], held: list[Step], beside: bool) -> tuple[float, float]:
    """A recurrent student's fit loss and held-out loss (``beside``: the project's policy, else sb3-contrib's)."""
    venv = training_env(config, seed=config.seed)
    if beside:
        model = build_model(config, venv)
    else:
        model = RecurrentPPO("MultiInputLstmPolicy", venv, seed=config.seed, device="cpu", **config.ppo.sb3_kwargs())
    venv.close()
    settings, bins, hidden = config.distill, config.action_bins, config.ppo.lstm_hidden_size
    optimizer = th.optim.Adam(model.policy.parameters(), lr=settings.learning_rate)
    loss = fit_sequences(model.policy, sequences(fit_on, settings.sequence_length, hidden), settings, optimizer, bins)
    test = sequences(held, settings.sequence_length, hidden).arrays()
    obs = {k: th.as_tensor(v).flatten(0, 1) for k, v in test["obs"].items()}
    state = (th.as_tensor(test["hidden"])[None], th.as_tensor(test["cell"])[None])
    with th.no_grad():
        distribution, _ = model.policy.get_distribution(obs, state, th.zeros(len(obs[next(iter(obs))])))
        held_loss = distribution_loss(distribution, th.as_tensor(test["labels"]).flatten(0, 1), bins,
                                      th.as_tensor(test["weights"]).flatten())
    return loss, float(held_loss)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="ClutterFly-v1", choices=["ClutterNav-v1", "ClutterFly-v1"])
    parser.add_argument("--fit", type=int, default=1500, help="vector steps fitted on")
    parser.add_argument("--held-out", type=int, default=500, help="vector steps held out, after them")
    parser.add_argument("--variants", nargs="+", default=["mlp", "between-8-600", "between-32-600", "between-8-64",
                                                          "beside-8-64", "beside-8-600"])
    parser.add_argument("--lstm", type=int, default=128, help="LSTM units of the recurrent students")
    args = parser.parse_args()
    th.set_num_threads(1)
    steps = collect(shipped(args.env), args.fit + args.held_out)
    fit_on, held = steps[:args.fit], steps[args.fit:]
    print(f"{args.env}: {args.fit} vector steps fitted on, {args.held_out} held out; the imitation loss\n")
    print("| student | fit | held out | seconds |\n|---|---|---|---|")
    for variant in args.variants:
        t0 = time.perf_counter()
        if variant == "mlp":
            losses = memoryless(shipped(args.env), fit_on, held)
        elif variant.startswith("conv-"):
            widths = [int(w) for w in variant.split("-")[1:]]
            losses = memoryless(shipped(args.env, ppo={"scan_conv": widths}), fit_on, held)
        else:
            kind, epochs, length = variant.split("-")
            config = shipped(args.env, ppo={"lstm_hidden_size": args.lstm})
            settings = dataclasses.replace(config.distill, epochs=int(epochs), sequence_length=int(length),
                                           batch_size=SEQUENCES_PER_BATCH * int(length))
            config = dataclasses.replace(config, distill=settings)
            losses = recurrent(config, fit_on, held, beside=kind == "beside")
        print(f"| {variant} | {losses[0]:.2f} | {losses[1]:.2f} | {time.perf_counter() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
