"""Policies and training tooling for clutter-gym envs (installed as ``clutter_gym.training``).

``load(run_dir)`` gives a trained run's :class:`Agent`; importing this package does not import torch (that
happens inside ``load``), so the command line stays quick.
"""

from clutter_gym.training.agent import Agent, load

__all__ = ["Agent", "load"]
