"""A multirotor moved by its reduced model (:mod:`clutter_gym.dynamics.flight_model`) wherever its step touches
nothing, and by full physics otherwise.

Each step is first flown by the model from a saved state. The model reports how far its centre of mass travelled and
how far it turned, so no point of the airframe moved further than ``travel + radius * turn`` (``radius``: the
farthest collision shape from the centre of mass). While that stays below the clearance FCL measured before the step,
less the contact tolerance, nothing can have touched: the step stands and pybullet is not stepped (nor read).
Otherwise the model's step is undone, the robot's pybullet body takes the model's pose, velocity and flight-controller
state, and the step runs under full physics; the model takes the next step back from pybullet's state. An episode
whose scene has a movable obstacle runs under full physics throughout.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clutter_gym.datatypes import CollisionReport, DynamicsSample, Obstacle, RobotState
from clutter_gym.dynamics.base import Dynamics, FullPhysics
from clutter_gym.dynamics.flight_model import (
    ANG,
    COM,
    HAS_VELOCITY,
    INTEGRAL,
    LIN,
    NOMINAL_THRUST,
    QUAT,
    RATIO,
    SPEEDS,
    TRAVEL,
    TURN,
    VELOCITY,
    flight_params,
    flight_ticks,
    rotor_table,
    state_size,
)
from clutter_gym.robots.multirotor import InnerState, Multirotor
from clutter_gym.sim import Sim
from clutter_gym.util.transforms import quat_to_matrix


class ReducedFlight(Dynamics):
    """See the module docstring.

    Args:
        radius: metres, the farthest point of the robot's collision shapes (padding included) from its centre of mass.
        contact_tolerance: metres, the env's: a clearance below it is a contact.

    Attributes:
        full: whether the last step ran under full physics (True at an episode's start).
        reduced_steps, full_steps: the steps run under each since the env was made.
    """

    def __init__(self, sim: Sim, robot: Multirotor, radius: float, contact_tolerance: float,
                 reason: str = "") -> None:
        self.sim, self.robot, self.radius, self.tolerance, self.reason = sim, robot, radius, contact_tolerance, reason
        self.physics = FullPhysics(sim, robot, reason)
        self.full, self._episode_full, self._on_body = True, True, True
        self.reduced_steps = self.full_steps = 0
        self._rotors = rotor_table(robot)
        self._model = np.zeros(state_size(len(self._rotors)))
        self._saved = self._model.copy()
        self._params = flight_params(robot, sim.physics_hz, sim.gravity)
        self._clearance = 0.0

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """The robot's body takes the sample (for the steps under full physics), the model the same mass, inertia and
        rotor strength."""
        self.physics.apply_dynamics(sample)
        self._params = flight_params(self.robot, self.sim.physics_hz, self.sim.gravity, sample.mass_scale,
                                     sample.motor_scale)

    def episode_start(self, obstacles: Sequence[Obstacle]) -> dict[str, object]:
        self._from_body()
        self._episode_full = any(o.movable for o in obstacles)
        self.full = True  # pybullet holds the drone at its start
        self._clearance = 0.0
        if self._episode_full:
            return {"model": "physics", "reason": "a movable obstacle in the scene: full physics for the episode"}
        return {"model": "reduced", "reason": self.reason}

    def advance(self, command: np.ndarray, substeps: int) -> None:
        robot, m = self.robot, self._model
        robot.apply_action(command)
        if not self._episode_full and self._clearance > self.tolerance:
            if self._on_body:
                self._from_body()
            self._saved[:] = m
            flight_ticks(m, self._params, self._rotors, robot.held_command(), substeps)
            if m[TRAVEL] + self.radius * m[TURN] + self.tolerance < self._clearance:
                self.reduced_steps += 1
                self.full, self._on_body = False, False
                robot.set_inner_state(self._inner())
                if self.sim.visuals:  # a camera or a rendered frame shows the robot where the model has it
                    self.sim.set_pose(robot.body, m[COM:COM + 3].tolist(), m[QUAT:QUAT + 4].tolist())
                return
            m[:] = self._saved  # the step may touch something: undone, and flown by pybullet
        if not self._on_body:
            self._to_body()
        self.full_steps += 1
        self.full = True
        self.physics.run(substeps)

    def state(self) -> RobotState:
        if self._on_body:
            return self.physics.state()
        m = self._model
        com, lin, ang = (tuple(m[i:i + 3].tolist()) for i in (COM, LIN, ANG))
        return self.robot.state_at(com, quat_to_matrix(m[QUAT:QUAT + 4]), lin, ang)

    def contacts(self) -> list[tuple[int, float]]:
        # a reduced step moved less than the clearance it began with: pybullet, not stepped, has no new contact
        return self.physics.contacts() if self._on_body else []

    def checked(self, report: CollisionReport) -> None:
        self._clearance = report.min_clearance

    # ------------------------------------------------------------------------------------------ hand-over
    def _inner(self) -> InnerState:
        m = self._model
        velocity = tuple(m[VELOCITY:VELOCITY + 3].tolist()) if m[HAS_VELOCITY] > 0.0 else None
        return InnerState(tuple(m[SPEEDS:].tolist()), tuple(m[INTEGRAL:INTEGRAL + 3].tolist()), float(m[RATIO]),
                          velocity, float(m[NOMINAL_THRUST]))

    def _from_body(self) -> None:
        """The model takes the robot's state from pybullet and the flight controller."""
        m, robot = self._model, self.robot
        m[COM:COM + 3], m[QUAT:QUAT + 4] = self.sim.base_pose(robot.body)
        _, _, lin, ang = self.sim.base_state(robot.body)
        inner = robot.inner_state()
        m[LIN:LIN + 3], m[ANG:ANG + 3] = lin, ang
        m[SPEEDS:], m[INTEGRAL:INTEGRAL + 3], m[RATIO] = inner.speeds, inner.integral, inner.ratio
        m[HAS_VELOCITY] = float(inner.velocity is not None)
        m[VELOCITY:VELOCITY + 3] = inner.velocity if inner.velocity is not None else (0.0, 0.0, 0.0)
        m[NOMINAL_THRUST] = inner.nominal_thrust
        self._on_body = True

    def _to_body(self) -> None:
        """The robot's pybullet body and flight controller take the model's state."""
        m, robot, sim = self._model, self.robot, self.sim
        sim.set_pose(robot.body, m[COM:COM + 3].tolist(), m[QUAT:QUAT + 4].tolist())
        sim.set_base_velocity(robot.body, m[LIN:LIN + 3].tolist(), m[ANG:ANG + 3].tolist())
        sim.record.forget_contacts(robot.body)
        robot.set_inner_state(self._inner())
        self._on_body = True
