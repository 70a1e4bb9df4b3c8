"""Policies and training tooling for clutter-gym envs (installed as ``clutter_gym.training``)."""
