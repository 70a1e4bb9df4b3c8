"""Tasks turn ground-truth state into named, weighted reward terms and episode-ending flags."""

from clutter_gym.datatypes import StepOutcome
from clutter_gym.tasks.fly import FlyRewardWeights, FlyTask
from clutter_gym.tasks.navigate import NavigateTask, NavRewardWeights
from clutter_gym.tasks.reach import ReachRewardWeights, ReachTask

__all__ = ["FlyRewardWeights", "FlyTask", "NavRewardWeights", "NavigateTask", "ReachRewardWeights", "ReachTask",
           "StepOutcome"]
