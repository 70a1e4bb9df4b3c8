"""The dynamics part of an env: what moves the robot through one control period and reads its state back.

:class:`FullPhysics` is pybullet's rigid-body simulation, every env's default. A reduced model
(:class:`~clutter_gym.dynamics.reduced_drive.ReducedDrive`) moves the robot without stepping pybullet while nothing
needs contact physics, and hands the step to a :class:`FullPhysics` when something does. The core calls, in a reset,
:meth:`Dynamics.apply_dynamics` before the scene is placed and :meth:`Dynamics.episode_start` once the robot stands at
its start; in a step, :meth:`Dynamics.advance`, :meth:`Dynamics.state`, :meth:`Dynamics.contacts` and, after the
collision check, :meth:`Dynamics.checked`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import cast

import numpy as np

from clutter_gym.datatypes import CollisionReport, DynamicsSample, Obstacle, RobotState
from clutter_gym.interfaces import Robot, TickedRobot
from clutter_gym.sim import Sim


class Dynamics:
    """The contract (see the module docstring); :class:`FullPhysics` is the reference implementation."""

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """This episode's dynamics randomisation (before the scene is placed)."""
        raise NotImplementedError

    def episode_start(self, obstacles: Sequence[Obstacle]) -> dict[str, object]:
        """The robot stands at rest at its start among ``obstacles``; returns what the reset's ``info["dynamics"]``
        says: the model the episode starts under and why."""
        raise NotImplementedError

    def advance(self, command: np.ndarray, substeps: int) -> None:
        """Drive the robot with the normalised ``command`` for one control period of ``substeps`` physics ticks."""
        raise NotImplementedError

    def state(self) -> RobotState:
        """The robot's state now."""
        raise NotImplementedError

    def contacts(self) -> list[tuple[int, float]]:
        """(other body id, signed distance m) of pybullet's contact points of the robot after the last advance."""
        raise NotImplementedError

    def checked(self, report: CollisionReport) -> None:
        """The collision check of :meth:`state` (at reset and after every step)."""


class FullPhysics(Dynamics):
    """pybullet's simulation: the robot's motors (or, for a :class:`~clutter_gym.interfaces.TickedRobot`, its
    per-tick controller) and the world stepped tick by tick."""

    def __init__(self, sim: Sim, robot: Robot, reason: str = "the env's settings") -> None:
        self.sim, self.robot, self.reason = sim, robot, reason
        # a TickedRobot (interfaces.py) acts before every physics tick; others once per action
        self._before_tick = cast(TickedRobot, robot).before_tick if getattr(robot, "ticked", False) else None

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        self.robot.apply_dynamics(sample)

    def episode_start(self, obstacles: Sequence[Obstacle]) -> dict[str, object]:
        return {"model": "physics", "reason": self.reason}

    def advance(self, command: np.ndarray, substeps: int) -> None:
        self.robot.apply_action(command)
        self.run(substeps)

    def run(self, substeps: int) -> None:
        """Step the world ``substeps`` ticks under the command the robot holds (a reduced part that has applied the
        action already hands its step over here)."""
        if self._before_tick is None:
            self.sim.step(substeps)
        else:
            for _ in range(substeps):
                self._before_tick()
                self.sim.step()

    def state(self) -> RobotState:
        return self.robot.state()

    def contacts(self) -> list[tuple[int, float]]:
        return self.sim.contact_distances(self.robot.body)


#: what an env takes as ``dynamics``: the part made from its Sim and its robot
DynamicsFactory = Callable[[Sim, Robot], Dynamics]
