"""clutter-gym: Gymnasium environments for robots in cluttered worlds. Importing it registers every env."""

from importlib.metadata import PackageNotFoundError, version

from gymnasium.envs.registration import register

from clutter_gym.vector import make_block_vector_env

try:
    __version__ = version("clutter-gym")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "0+unknown"

ENV_IDS = ("ClutterNav-v1", "ClutterReach-v1", "ClutterFly-v1")
#: Each env with the env arguments its shipped PPO agent trains with (training/hyperparams/ppo.yml), under an id of
#: its own, for tools that make envs by id alone: rl-zoo3 makes its evaluation env without the conf file's
#: env_kwargs. Making one needs no training extra; keyword arguments go on top of the shipped ones.
TRAIN_IDS = {"ClutterNavTrain-v1": "ClutterNav-v1", "ClutterReachTrain-v1": "ClutterReach-v1",
             "ClutterFlyTrain-v1": "ClutterFly-v1"}

#: The ids of clutter-gym 0.2.0 and before, whose results at defaults 0.3.0 changed (CHANGELOG.md, 0.3.0): they
#: are no longer registered, so gym.make names the new id, and a run folder trained on one is read as the new id's.
RENAMED_IDS = {"ClutterNav-v0": "ClutterNav-v1", "ClutterReach-v0": "ClutterReach-v1", "ClutterFly-v0": "ClutterFly-v1"}

_ENTRY_POINTS = {"ClutterNav-v1": "clutter_gym.clutter_nav:ClutterNavEnv",
                 "ClutterReach-v1": "clutter_gym.clutter_reach:ClutterReachEnv",
                 "ClutterFly-v1": "clutter_gym.clutter_fly:ClutterFlyEnv"}
_EPISODE_STEPS = {"ClutterNav-v1": 400, "ClutterReach-v1": 100, "ClutterFly-v1": 600}
for _env_id in ENV_IDS:  # gym.make_vec's default for them: their envs in blocks over the cores (clutter_gym.vector)
    register(id=_env_id, entry_point=_ENTRY_POINTS[_env_id], max_episode_steps=_EPISODE_STEPS[_env_id],
             vector_entry_point=make_block_vector_env(_env_id))
#: ClutterReach goal-conditioned for HER: Dict(observation, achieved_goal, desired_goal) and compute_reward.
register(id="ClutterReachGoal-v1", entry_point="clutter_gym.goal_conditioned:ClutterReachGoalEnv",
         max_episode_steps=_EPISODE_STEPS["ClutterReach-v1"])
for _train_id, _env_id in TRAIN_IDS.items():
    register(id=_train_id, entry_point="clutter_gym.training.zoo:shipped_env", kwargs={"env_id": _env_id},
             max_episode_steps=_EPISODE_STEPS[_env_id])

__all__ = ["ENV_IDS", "RENAMED_IDS", "TRAIN_IDS", "__version__"]
