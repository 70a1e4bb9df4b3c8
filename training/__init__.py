"""Policies and training tooling for clutter-gym envs (installed as ``clutter_gym.training``).

``load(run_dir)`` gives a trained run's :class:`Agent`. Importing this package imports stable-baselines3 and
torch.
"""

from clutter_gym.training.agent import Agent, load

__all__ = ["Agent", "load"]
