"""A multirotor on rotor forces: any rigid airframe a :class:`MultirotorModel` describes (``robots/quadrotor.py``
holds the built-in Crazyflie-sized quadrotor's; ``robots/multirotor_model.py`` reads a user's from a spec).

It flies on forces alone: before every physics tick (:meth:`Multirotor.before_tick`) the inner loop turns the held
command into rotor speed commands, the motors follow them with a first-order lag, and each rotor's thrust is
applied at its hub, with the rotors' drag-reaction torque on the body. Attitude therefore comes from the physics
engine, never from setting a pose. The quadrotor's coefficients, limits and their sources: docs/quadrotor.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import DynamicsSample, RobotState
from clutter_gym.robots.aero import AERO_EFFECTS, ground_effect_gain, rotor_drag
from clutter_gym.robots.dynamics import scale_link_dynamics
from clutter_gym.robots.multirotor_model import MultirotorModel, check_ranges, in_principal_axes, layout_problem
from clutter_gym.robots.rate_loop import Mixer, RateController, RateGains
from clutter_gym.robots.rigid_body import RigidFrames, rigid_body
from clutter_gym.robots.thrust_estimate import RATIO_BOUNDS, ThrustRatioEstimator
from clutter_gym.robots.urdf_robot import UrdfRobot
from clutter_gym.sim import Sim
from clutter_gym.util.transforms import quat_to_matrix, times, times_transposed, yaw_quat

CONTROL_MODES = ("rates", "motors")
#: Bound of the observed body-frame linear velocity, m/s (faster readings are clipped).
MAX_OBSERVED_SPEED = 20.0

_ZERO = (0.0, 0.0, 0.0)
#: (low, high, low_open) of every number field: low < value (low_open) or low <= value, and value <= high
_RANGES = {
    "max_roll_rate": (0.0, 20.0, True),
    "max_pitch_rate": (0.0, 20.0, True),
    "max_yaw_rate": (0.0, 10.0, True),
    "rate_kp_roll_pitch": (0.0, 200.0, True),
    "rate_kp_yaw": (0.0, 200.0, True),
    "rate_ki_roll_pitch": (0.0, 1000.0, False),
    "rate_ki_yaw": (0.0, 1000.0, False),
    "rate_integral_limit": (0.0, 10.0, True),
    "thrust_ratio_time_constant": (0.0, 10.0, True),
}


@dataclass(frozen=True)
class MultirotorConfig:
    """Control mode, inner loop and aerodynamic effects of a multirotor (defaults: docs/quadrotor.md, with sources);
    its rotors and their coefficients are its :class:`MultirotorModel`'s.

    Attributes:
        control: ``"rates"``: action = (collective thrust, roll rate, pitch rate, yaw rate), tracked by the inner
            rate loop; ``"motors"``: action = one speed command per rotor.
        max_roll_rate: body roll rate of action[1] = 1, rad/s.
        max_pitch_rate: body pitch rate of action[2] = 1, rad/s.
        max_yaw_rate: body yaw rate of action[3] = 1, rad/s.
        rate_kp_roll_pitch: proportional gain of the roll and pitch rate loops, 1/s.
        rate_kp_yaw: proportional gain of the yaw rate loop, 1/s.
        rate_ki_roll_pitch: integral gain of the roll and pitch rate loops, 1/s^2.
        rate_ki_yaw: integral gain of the yaw rate loop, 1/s^2.
        rate_integral_limit: bound of each axis' integrated rate error, rad.
        aero: aerodynamic effects on, a subset of ``("drag", "ground_effect")`` (empty: none), with the model's
            drag coefficients and rotor radius.
        start_hovering: episodes start with every rotor at the nominal hover speed (else stopped).
        observe_thrust_ratio: add the ``thrust_ratio`` observation, the flight controller's estimate of the
            thrust the airframe gets against its nominal model (:mod:`clutter_gym.robots.thrust_estimate`).
        thrust_ratio_time_constant: seconds, of that estimate's filter.
    """

    control: str = "rates"
    max_roll_rate: float = 3.0
    max_pitch_rate: float = 3.0
    max_yaw_rate: float = 2.0
    rate_kp_roll_pitch: float = 10.0
    rate_kp_yaw: float = 10.0
    rate_ki_roll_pitch: float = 0.0
    rate_ki_yaw: float = 0.0
    rate_integral_limit: float = 0.5
    aero: tuple[str, ...] = ()
    start_hovering: bool = True
    observe_thrust_ratio: bool = False
    thrust_ratio_time_constant: float = 0.25

    def __post_init__(self) -> None:
        if self.control not in CONTROL_MODES:
            raise ValueError(f"control must be one of {CONTROL_MODES}, got {self.control!r}")
        check_ranges({name: getattr(self, name) for name in _RANGES}, _RANGES)
        if not (isinstance(self.aero, tuple) and set(self.aero) <= set(AERO_EFFECTS)
                and len(set(self.aero)) == len(self.aero)):
            raise ValueError(f"aero must be a tuple of distinct names from {AERO_EFFECTS}, got {self.aero!r}")
        for name in ("start_hovering", "observe_thrust_ratio"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be True or False, got {getattr(self, name)!r}")

    def rate_gains(self) -> RateGains:
        """The rate loop's gains, (roll, pitch, yaw)."""
        rp, y = self.rate_kp_roll_pitch, self.rate_kp_yaw
        return RateGains((rp, rp, y), (self.rate_ki_roll_pitch, self.rate_ki_roll_pitch, self.rate_ki_yaw),
                         self.rate_integral_limit)


class InnerState(NamedTuple):
    """The flight controller's state between ticks: rotor speeds (rad/s), the rate loop's integral (rad), the
    thrust-ratio estimate, the estimator's last velocity (m/s, None before its first tick) and the nominal thrust of
    the last tick (N)."""

    speeds: tuple[float, ...]
    integral: tuple[float, float, float]
    ratio: float
    velocity: tuple[float, float, float] | None
    nominal_thrust: float


class Multirotor(UrdfRobot):
    """Rate- or motor-commanded multirotor on per-rotor forces.

    Action: with ``control="rates"``, Box(-1, 1, (4,)): ``T = (a0 + 1) / 2 * T_max`` (N, collective thrust, 0 to
    ``T_max``, the most the rotors give without a torque: the four rotors' maximum on the quadrotor) and body rates
    ``(p, q, r) = (a1, a2, a3) * (max_roll_rate, max_pitch_rate, max_yaw_rate)`` (rad/s, body frame,
    counter-clockwise positive about x forward, y left, z up); the rate loop (:mod:`clutter_gym.robots.rate_loop`)
    and the mixer turn them into rotor speed commands at the physics rate. With ``control="motors"``, Box(-1, 1,
    (n rotors,)): rotor ``i``'s speed command is ``w_min + (a_i + 1) / 2 * (w_max - w_min)`` (rad/s), in the model's
    ``rotor_links`` order.

    The inner loop uses the nominal model (URDF mass and inertia, the model's coefficients); per-episode dynamics
    (:meth:`apply_dynamics`) change the simulated mass and the rotors' thrust and torque, not the model, as an
    airframe differs from its datasheet. pybullet's velocity damping is off: the only drag is the optional
    ``aero`` model.

    Attributes:
        ticked: the robot needs :meth:`before_tick` before every physics tick (the env steps tick by tick).
        model: the airframe: URDF, rotor links and spins, rotor coefficients.
        mass_properties: mass, centre of mass, inertia and link frames of the URDF, the inner loop's plant model.
        rotors: the rotor model.
        mixer: rotor thrusts from the rate loop's collective thrust and torques.

    Raises:
        ValueError: the rotors cannot fly the airframe (``multirotor_model.layout_problem``), or ``aero`` asks for
            rotor drag of a model that has none.
    """

    ticked = True

    def __init__(self, model: MultirotorModel, config: MultirotorConfig | None = None) -> None:
        self.model = m = model
        self.name, self.base_link = m.name, m.base_link
        self.config = c = config or MultirotorConfig()
        if "drag" in c.aero and m.drag_xy == m.drag_z == 0.0:
            raise ValueError(f"aero 'drag' needs rotor drag coefficients: robot {m.name!r} has drag_xy = drag_z = 0 "
                             "(give them in its spec)")
        n = len(m.rotor_links)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(4 if c.control == "rates" else n,), dtype=np.float32)
        rate_bound = 2.0 * max(c.max_roll_rate, c.max_pitch_rate, c.max_yaw_rate)
        self._velocity_bound = np.array([MAX_OBSERVED_SPEED] * 3 + [rate_bound] * 3)
        self.spaces = {
            "rotor_speeds": spaces.Box(0.0, 1.0, shape=(n,), dtype=np.float32),
            "attitude": spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32),
            "velocity": spaces.Box(-self._velocity_bound.astype(np.float32), self._velocity_bound.astype(np.float32),
                                   dtype=np.float32),
        }
        if c.observe_thrust_ratio:
            self.spaces["thrust_ratio"] = spaces.Box(*RATIO_BOUNDS, shape=(1,), dtype=np.float32)
        self.rotors = m.rotor_model()
        self.mass_properties = body = rigid_body(self.urdf_path)
        problem = layout_problem(m.allocation(body), m.spin)
        if problem:
            raise ValueError(f"robot {m.name!r}: {problem}")
        self._frames = RigidFrames(body, m.tracked_links)
        self.mixer = Mixer(m.allocation(body), self.rotors.min_thrust, self.rotors.max_thrust)
        self._max_collective = self.rotors.max_thrust / max(self.mixer.shares)  # N, the rates mode's a0 = 1
        self._hubs = [tuple(body.frames[link][0] - body.com) for link in m.rotor_links]  # body frame, m
        self._rate_scale = (c.max_roll_rate, c.max_pitch_rate, c.max_yaw_rate)
        self._rates = c.control == "rates"
        self._drag = "drag" in c.aero
        self._ground_effect = "ground_effect" in c.aero
        self._controller: RateController | None = None
        self._estimator: ThrustRatioEstimator | None = None
        self._nominal_thrust = 0.0  # N, the model's thrust over the last tick (what the estimator compares)
        self._decay = 0.0
        self._thrust_scale = 1.0  # the episode's motor strength
        # per-tick state and commands as Python floats (before_tick's arithmetic is on floats)
        self._speeds = [0.0] * n
        self._speed_command = [0.0] * n
        self._thrust_command = 0.0
        self._rate_command = [0.0] * 3

    @property
    def urdf_path(self) -> Path:
        return self.model.urdf

    @property
    def rotor_speeds(self) -> np.ndarray:
        """Current rotor speeds, rad/s, in ``rotor_links`` order (a new array)."""
        return np.array(self._speeds)

    def hover_speeds(self, gravity: float) -> list[float]:
        """Rotor speeds (rad/s) at which the nominal rotors carry the nominal weight level, each its share."""
        mass, kf = self.mass_properties.mass, self.model.thrust_coefficient
        return [math.sqrt(share * mass * gravity / kf) for share in self.mixer.shares]

    def hover_action(self, gravity: float) -> np.ndarray:
        """The action that holds a level hover at rest in the configured control mode (zero rates)."""
        c, m = self.config, self.model
        if c.control == "rates":
            thrust = self.mass_properties.mass * gravity / self._max_collective
            return np.array([2.0 * thrust - 1.0, 0.0, 0.0, 0.0])
        levels = [(w - m.min_rotor_speed) / (m.max_rotor_speed - m.min_rotor_speed) for w in self.hover_speeds(gravity)]
        return np.array([2.0 * level - 1.0 for level in levels])

    def load(self, sim: Sim) -> int:
        """Load the URDF into ``sim`` as one rigid body with the airframe's mass and inertia, and switch off velocity
        damping.

        The airframe's links are merged into one pybullet body (``Sim.load_urdf(merge_fixed_links=True)``): its
        fixed joints add nothing but cost, and the tracked links' states follow from the base's
        (:class:`RigidFrames`). pybullet recomputes the inertia from the collision shapes when it loads a URDF; the
        URDF's, composed over its links, is set back here, and it is the nominal value :meth:`apply_dynamics` scales.

        Raises:
            ValueError: the merged body's centre of mass is not the URDF's (mass on a link off its origin), or its
                inertia has products of inertia (pybullet takes principal moments only).
        """
        self._load(sim, merge_fixed_links=True)
        sim.actuation.set_damping(self._body, 0.0, 0.0)
        # one colour: a camera hides the merged body and shows it again
        sim.rendering.paint(self._body, self.model.colour)
        self.link_index = sim.link_indices(self._body)  # the merged body's: the tracked links follow from the base
        self.link_names = self.model.tracked_links
        body = self.mass_properties
        self._com_offset = sim.base_inertial_offset(self._body)
        if np.abs(self._com_offset - body.com).max() > 1e-9:
            raise ValueError(f"{self.urdf_path}: the merged body's centre of mass {self._com_offset.tolist()} is not "
                             f"the URDF's {body.com.tolist()}: put the airframe's mass on {self.base_link}")
        dt = 1.0 / sim.physics_hz
        self._decay = self.rotors.decay(dt)
        self._controller = RateController(body.inertia, self.config.rate_gains(), dt)
        self._gravity = sim.gravity
        if self.config.observe_thrust_ratio:
            self._estimator = ThrustRatioEstimator(body.mass, sim.gravity, dt, self.config.thrust_ratio_time_constant)
        if not in_principal_axes(body.inertia):
            raise ValueError(f"{self.urdf_path}: give the airframe's inertia in principal axes, got "
                             f"{body.inertia.tolist()}")
        (_, friction, _), = sim.actuation.inertial_properties(self._body, [-1])
        self._nominal = {-1: (body.mass, friction, tuple(np.diag(body.inertia).tolist()))}
        scale_link_dynamics(sim, self._body, self._nominal, DynamicsSample())
        self._thrust_scale = 1.0
        return self._body

    def _set_motor_scale(self, scale: float) -> None:
        """The rotors' thrust and torque scale with the motor strength (the inner loop keeps the nominal model)."""
        self._thrust_scale = float(scale)

    def reset_to(self, start: tuple[float, ...]) -> None:
        """Place the robot at rest at ``start`` = (x m, y m, z m of the base frame, yaw rad), level; the rotors
        spin at hover speed (``start_hovering``) or stand, and the command holds that state."""
        x, y, z, yaw = start
        q = yaw_quat(yaw)
        com = np.array([x, y, z]) + quat_to_matrix(np.array(q)) @ self._com_offset
        self._sim.set_pose(self._body, com, q)
        self._sim.record.forget_contacts(self._body)
        self._controller.reset()
        if self._estimator is not None:
            self._estimator.reset()
        lo, hi = self.model.min_rotor_speed, self.model.max_rotor_speed
        if self.config.start_hovering:
            self._speeds = [min(max(w, lo), hi) for w in self.hover_speeds(self._gravity)]
            self.apply_action(self.hover_action(self._gravity))
        else:
            self._speeds = [lo] * len(self._speeds)
            self.apply_action(-np.ones(self.action_space.shape))

    def apply_action(self, action: np.ndarray) -> None:
        """Hold a clipped, normalised action as the command of the coming ticks."""
        a = np.asarray(action, dtype=float)
        if self._rates:
            self._thrust_command = float(0.5 * (a[0] + 1.0) * self._max_collective)
            self._rate_command = [u * scale for u, scale in zip(a[1:4].tolist(), self._rate_scale)]
        else:
            m = self.model
            command = m.min_rotor_speed + 0.5 * (a + 1.0) * (m.max_rotor_speed - m.min_rotor_speed)
            self._speed_command = command.tolist()

    def held_command(self) -> np.ndarray:
        """The command the coming ticks hold: (collective thrust N, body rates rad/s) with ``control="rates"``, one
        speed command per rotor (rad/s) otherwise."""
        if self._rates:
            return np.array([self._thrust_command, *self._rate_command])
        return np.array(self._speed_command)

    def inner_state(self) -> InnerState:
        """What the flight controller holds between ticks (a reduced model of the flight takes it over)."""
        e = self._estimator
        if e is None:
            return InnerState(tuple(self._speeds), self._controller.integral, 1.0, None, self._nominal_thrust)
        return InnerState(tuple(self._speeds), self._controller.integral, e.ratio, e.velocity, self._nominal_thrust)

    def set_inner_state(self, inner: InnerState) -> None:
        """Take over the flight controller's state from a reduced model of the flight."""
        self._speeds = list(inner.speeds)
        self._controller.integral = inner.integral
        self._nominal_thrust = inner.nominal_thrust
        if self._estimator is not None:
            self._estimator.ratio, self._estimator.velocity = inner.ratio, inner.velocity

    def before_tick(self) -> None:
        """One physics tick of actuation: inner loop, motor lag, then rotor forces and the body torque for the
        next ``stepSimulation`` (which clears them). Rotor speeds advance first, so a tick's forces come from the
        speeds at its end.

        All on Python floats: the vectors are 3 long and one entry per rotor, where numpy's cost per call outweighs the
        arithmetic.
        """
        sim, rotors, scale = self._sim, self.rotors, self._thrust_scale
        com, rot, lin, ang = sim.base_state(self._body)
        if self._estimator is not None:  # the velocity the last tick's thrust produced
            self._estimator.update((rot[2], rot[5], rot[8]), lin, self._nominal_thrust)
        if self._rates:
            torque = self._controller.torque(self._rate_command, times_transposed(rot, ang))
            command = rotors.speed_for_thrust(self.mixer.thrusts(self._thrust_command, torque))
        else:
            command = self._speed_command
        self._speeds = speeds = rotors.step(self._speeds, command, self._decay)
        nominal = rotors.thrust(speeds)
        if self._estimator is not None:
            self._nominal_thrust = sum(nominal)
        thrusts = [f * scale for f in nominal]
        if self._ground_effect and rot[8] > 0.0:  # upright: the rotors blow towards the ground
            _, _, z = com
            ux, uy, uz = rot[6:9]  # the world's up axis in the body frame
            heights = [z + (ux * x + uy * y + uz * h) for x, y, h in self._hubs]
            thrusts = [f * gain for f, gain in zip(thrusts, ground_effect_gain(heights, self.model.rotor_radius))]
        sim.actuation.apply_base_forces(self._body, [(0.0, 0.0, f) for f in thrusts], self._hubs)
        yaw = rotors.yaw_torque(speeds, self.model.spin) * scale
        if self._drag:
            drag = rotor_drag(times_transposed(rot, lin), speeds, self.model.drag_xy, self.model.drag_z)
            force = times(rot, drag)
        else:
            force = _ZERO
        sim.actuation.apply_base_wrench(self._body, force, (yaw * rot[2], yaw * rot[5], yaw * rot[8]))

    def state(self) -> RobotState:
        """Ground-truth state from one pybullet read of the base: the airframe is rigid, so the tracked links'
        states follow from the base's (:class:`RigidFrames`)."""
        com, rot, lin, ang = self._sim.base_state(self._body)
        return self.state_at(com, np.reshape(rot, (3, 3)), lin, ang)

    def state_at(self, com: Sequence[float], rotation: np.ndarray, linear_velocity: Sequence[float],
                 angular_velocity: Sequence[float]) -> RobotState:
        """The state of the airframe whose centre of mass is at ``com`` (world, m) with ``rotation`` (3, 3) and the
        velocities of its centre of mass (world, m/s and rad/s): pybullet's, or a reduced model's."""
        return RobotState(
            position=np.asarray(com) - rotation @ self._com_offset,
            rotation=rotation,
            linear_velocity=linear_velocity,
            angular_velocity=angular_velocity,
            links=self._frames.link_states(com, rotation, linear_velocity, angular_velocity),
            link_names=self.link_names,
            link_index=self.link_index,
            body=self._body,
        )

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """The base origin (world frame, metres) and the radius that encloses the rotors: what the ``rgb_array``
        view rings."""
        return state.position, self.model.focus_radius

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """Proprioception, as a flight controller's state estimate gives it (ground truth here):

        * ``rotor_speeds``: each rotor's speed over ``max_rotor_speed``, in [0, 1] (an RPM sensor's reading);
        * ``attitude``: the world's up axis in the body frame (x forward, y left, z up), a unit vector: (0, 0, 1)
          when level, its z the cosine of the tilt;
        * ``velocity``: body-frame linear velocity (m/s, clipped to +-``MAX_OBSERVED_SPEED``) then body rates
          (rad/s, clipped to +-2x the largest commanded rate);
        * ``thrust_ratio`` (with ``observe_thrust_ratio``): the estimated thrust per unit mass over the nominal
          model's, (1,), within ``RATIO_BOUNDS``.
        """
        rot = state.rotation
        body = np.concatenate([rot.T @ np.asarray(state.linear_velocity), rot.T @ np.asarray(state.angular_velocity)])
        obs = {
            "rotor_speeds": (np.array(self._speeds) / self.model.max_rotor_speed).astype(np.float32),
            "attitude": np.clip(rot[2], -1.0, 1.0).astype(np.float32),
            "velocity": np.clip(body, -self._velocity_bound, self._velocity_bound).astype(np.float32),
        }
        if self._estimator is not None:
            obs["thrust_ratio"] = np.array([self._estimator.ratio], dtype=np.float32)
        return obs
