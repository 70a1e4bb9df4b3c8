"""clutter-gym: Gymnasium environments for robots in cluttered worlds. Importing it registers every env."""

from importlib.metadata import PackageNotFoundError, version

from gymnasium.envs.registration import register

try:
    __version__ = version("clutter-gym")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "0+unknown"

ENV_IDS = ("ClutterNav-v0", "ClutterReach-v0", "ClutterFly-v0")

register(id="ClutterNav-v0", entry_point="clutter_gym.clutter_nav:ClutterNavEnv", max_episode_steps=400)
register(id="ClutterReach-v0", entry_point="clutter_gym.clutter_reach:ClutterReachEnv", max_episode_steps=100)
register(id="ClutterFly-v0", entry_point="clutter_gym.clutter_fly:ClutterFlyEnv", max_episode_steps=600)

__all__ = ["ENV_IDS", "__version__"]
