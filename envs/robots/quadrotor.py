"""Quadrotor (assets/robots/quadrotor.urdf): a Crazyflie-2.x-sized X-configuration nano quadrotor on rotor forces.

It flies on forces alone: before every physics tick (:meth:`Quadrotor.before_tick`) the inner loop turns the held
command into rotor speed commands, the motors follow them with a first-order lag, and each rotor's thrust is
applied at its hub, with the rotors' drag-reaction torque on the body. Attitude therefore comes from the physics
engine, never from setting a pose. Coefficients, limits and their sources: docs/quadrotor.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
from gymnasium import spaces

from clutter_gym.assets import asset_path
from clutter_gym.datatypes import DynamicsSample, RobotState
from clutter_gym.robots.aero import AERO_EFFECTS, ground_effect_gain, rotor_drag
from clutter_gym.robots.dynamics import scale_link_dynamics
from clutter_gym.robots.rate_loop import Mixer, RateController, RateGains, allocation
from clutter_gym.robots.rigid_body import RigidFrames, rigid_body
from clutter_gym.robots.rotors import RotorModel
from clutter_gym.robots.thrust_estimate import RATIO_BOUNDS, ThrustRatioEstimator
from clutter_gym.robots.urdf_robot import UrdfRobot
from clutter_gym.sim import Sim
from clutter_gym.util.checks import is_number
from clutter_gym.util.transforms import quat_to_matrix, yaw_quat

ROTOR_LINKS = ("rotor_1", "rotor_2", "rotor_3", "rotor_4")
#: Spin of each rotor of ``ROTOR_LINKS``: +1 counter-clockwise seen from above. Diagonal rotors turn alike, so equal
#: speeds cancel their drag torques; rotor_1 (front right) turns counter-clockwise.
ROTOR_SPIN = (1.0, -1.0, 1.0, -1.0)
#: Links whose states are read every control step: every link with collision geometry, the IMU and the sensor mount.
TRACKED_LINKS = ("battery", "arm_1", "arm_2", "arm_3", "arm_4", *ROTOR_LINKS, "imu", "sensor_mount")
RING_RADIUS = 0.066  # metres from the base origin to a propeller tip, as in the URDF
CONTROL_MODES = ("rates", "motors")
#: The whole airframe's colour in renders (the URDF's "frame" material): a merged body's base takes one colour.
AIRFRAME_COLOUR = (0.15, 0.15, 0.15, 1.0)
#: Bound of the observed body-frame linear velocity, m/s (faster readings are clipped).
MAX_OBSERVED_SPEED = 20.0

_ZERO = (0.0, 0.0, 0.0)
#: (low, high, low_open) of every number field: low < value (low_open) or low <= value, and value <= high
_RANGES = {
    "thrust_coefficient": (0.0, 1e-4, True),
    "torque_coefficient": (0.0, 1e-5, False),
    "motor_time_constant": (0.0, 1.0, False),
    "min_rotor_speed": (0.0, 1e4, False),
    "max_rotor_speed": (0.0, 1e4, True),
    "max_roll_rate": (0.0, 20.0, True),
    "max_pitch_rate": (0.0, 20.0, True),
    "max_yaw_rate": (0.0, 10.0, True),
    "rate_kp_roll_pitch": (0.0, 200.0, True),
    "rate_kp_yaw": (0.0, 200.0, True),
    "rate_ki_roll_pitch": (0.0, 1000.0, False),
    "rate_ki_yaw": (0.0, 1000.0, False),
    "rate_integral_limit": (0.0, 10.0, True),
    "drag_xy": (0.0, 1e-3, False),
    "drag_z": (0.0, 1e-3, False),
    "rotor_radius": (0.0, 0.5, True),
    "thrust_ratio_time_constant": (0.0, 10.0, True),
}


@dataclass(frozen=True)
class QuadrotorConfig:
    """Actuation, inner loop and aerodynamics of the quadrotor (defaults: docs/quadrotor.md, with sources).

    Attributes:
        control: ``"rates"``: action = (collective thrust, roll rate, pitch rate, yaw rate), tracked by the inner
            rate loop; ``"motors"``: action = one speed command per rotor.
        thrust_coefficient: kf, N / (rad/s)^2.
        torque_coefficient: km, N m / (rad/s)^2.
        motor_time_constant: first-order lag of the rotor speeds, seconds (0: none).
        min_rotor_speed: rad/s; action -1 of the motor mode.
        max_rotor_speed: rad/s; action +1 of the motor mode, and the collective thrust of action[0] = 1.
        max_roll_rate: body roll rate of action[1] = 1, rad/s.
        max_pitch_rate: body pitch rate of action[2] = 1, rad/s.
        max_yaw_rate: body yaw rate of action[3] = 1, rad/s.
        rate_kp_roll_pitch: proportional gain of the roll and pitch rate loops, 1/s.
        rate_kp_yaw: proportional gain of the yaw rate loop, 1/s.
        rate_ki_roll_pitch: integral gain of the roll and pitch rate loops, 1/s^2.
        rate_ki_yaw: integral gain of the yaw rate loop, 1/s^2.
        rate_integral_limit: bound of each axis' integrated rate error, rad.
        drag_xy: rotor-induced drag coefficient along body x and y, kg/rad (``"drag"`` in ``aero``).
        drag_z: rotor-induced drag coefficient along body z, kg/rad.
        rotor_radius: propeller radius for the ground effect, metres.
        aero: aerodynamic effects on, a subset of ``("drag", "ground_effect")`` (empty: none).
        start_hovering: episodes start with every rotor at the nominal hover speed (else stopped).
        observe_thrust_ratio: add the ``thrust_ratio`` observation, the flight controller's estimate of the
            thrust the airframe gets against its nominal model (:mod:`clutter_gym.robots.thrust_estimate`).
        thrust_ratio_time_constant: seconds, of that estimate's filter.
    """

    control: str = "rates"
    thrust_coefficient: float = 2.8816e-8
    torque_coefficient: float = 1.7187e-10
    motor_time_constant: float = 0.05
    min_rotor_speed: float = 0.0
    max_rotor_speed: float = 2272.7
    max_roll_rate: float = 3.0
    max_pitch_rate: float = 3.0
    max_yaw_rate: float = 2.0
    rate_kp_roll_pitch: float = 10.0
    rate_kp_yaw: float = 10.0
    rate_ki_roll_pitch: float = 0.0
    rate_ki_yaw: float = 0.0
    rate_integral_limit: float = 0.5
    drag_xy: float = 9.1785e-7
    drag_z: float = 10.311e-7
    rotor_radius: float = 0.0231348
    aero: tuple[str, ...] = ()
    start_hovering: bool = True
    observe_thrust_ratio: bool = False
    thrust_ratio_time_constant: float = 0.25

    def __post_init__(self) -> None:
        if self.control not in CONTROL_MODES:
            raise ValueError(f"control must be one of {CONTROL_MODES}, got {self.control!r}")
        for field in fields(self):
            if field.name not in _RANGES:
                continue
            lo, hi, low_open = _RANGES[field.name]
            value = getattr(self, field.name)
            number = is_number(value) and math.isfinite(value)
            if not (number and (lo < value if low_open else lo <= value) and value <= hi):
                bracket = "(" if low_open else "["
                raise ValueError(f"{field.name} must be a number in {bracket}{lo}, {hi}], got {value!r}")
        if self.min_rotor_speed >= self.max_rotor_speed:
            raise ValueError(
                f"min_rotor_speed must be in [0, max_rotor_speed={self.max_rotor_speed}), got {self.min_rotor_speed!r}"
            )
        if not (isinstance(self.aero, tuple) and set(self.aero) <= set(AERO_EFFECTS)
                and len(set(self.aero)) == len(self.aero)):
            raise ValueError(f"aero must be a tuple of distinct names from {AERO_EFFECTS}, got {self.aero!r}")
        for name in ("start_hovering", "observe_thrust_ratio"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be True or False, got {getattr(self, name)!r}")

    def rotor_model(self) -> RotorModel:
        """The rotors these values describe."""
        return RotorModel(self.thrust_coefficient, self.torque_coefficient, self.motor_time_constant,
                          self.min_rotor_speed, self.max_rotor_speed)

    def rate_gains(self) -> RateGains:
        """The rate loop's gains, (roll, pitch, yaw)."""
        rp, y = self.rate_kp_roll_pitch, self.rate_kp_yaw
        return RateGains((rp, rp, y), (self.rate_ki_roll_pitch, self.rate_ki_roll_pitch, self.rate_ki_yaw),
                         self.rate_integral_limit)


class Quadrotor(UrdfRobot):
    """Rate- or motor-commanded quadrotor on per-rotor forces.

    Action: Box(-1, 1, (4,)). With ``control="rates"``: ``T = (a0 + 1) / 2 * 4 kf w_max^2`` (N, collective
    thrust, 0 to the four rotors' maximum) and body rates ``(p, q, r) = (a1, a2, a3) * (max_roll_rate,
    max_pitch_rate, max_yaw_rate)`` (rad/s, body frame, counter-clockwise positive about x forward, y left, z up);
    the rate loop (:mod:`clutter_gym.robots.rate_loop`) and the mixer turn them into rotor speed commands at the
    physics rate. With ``control="motors"``: rotor ``i``'s speed command is
    ``w_min + (a_i + 1) / 2 * (w_max - w_min)`` (rad/s), in ``ROTOR_LINKS`` order.

    The inner loop uses the nominal model (URDF mass and inertia, configured coefficients); per-episode dynamics
    (:meth:`apply_dynamics`) change the simulated masses and the rotors' thrust and torque, not the model, as an
    airframe differs from its datasheet. pybullet's velocity damping is off: the only drag is the optional
    ``aero`` model.

    Attributes:
        ticked: the robot needs :meth:`before_tick` before every physics tick (the env steps tick by tick).
        model: mass properties of the URDF (mass, centre of mass, inertia), the inner loop's plant model.
        rotors: the rotor model.
    """

    name = "quadrotor"
    base_link = "base_link"
    urdf = "robots/quadrotor.urdf"
    ticked = True

    def __init__(self, config: QuadrotorConfig | None = None) -> None:
        self.config = c = config or QuadrotorConfig()
        self.action_space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)
        rate_bound = 2.0 * max(c.max_roll_rate, c.max_pitch_rate, c.max_yaw_rate)
        self._velocity_bound = np.array([MAX_OBSERVED_SPEED] * 3 + [rate_bound] * 3)
        self.spaces = {
            "rotor_speeds": spaces.Box(0.0, 1.0, shape=(4,), dtype=np.float32),
            "attitude": spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32),
            "velocity": spaces.Box(-self._velocity_bound.astype(np.float32), self._velocity_bound.astype(np.float32),
                                   dtype=np.float32),
        }
        if c.observe_thrust_ratio:
            self.spaces["thrust_ratio"] = spaces.Box(*RATIO_BOUNDS, shape=(1,), dtype=np.float32)
        self.rotors = c.rotor_model()
        self.model = rigid_body(self.urdf_path)
        self._frames = RigidFrames(self.model, TRACKED_LINKS)
        hubs = np.array([self.model.frames[n][0] - self.model.com for n in ROTOR_LINKS])
        alloc = allocation(hubs[:, :2], np.array(ROTOR_SPIN), c.torque_coefficient / c.thrust_coefficient)
        self.mixer = Mixer(alloc, self.rotors.min_thrust, self.rotors.max_thrust)
        base_com = self.model.link_coms[self.model.root]  # pybullet's base position: forces and heights from there
        self._hubs = [tuple(self.model.frames[n][0] - base_com) for n in ROTOR_LINKS]  # body frame, m
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
        self._speeds = [0.0] * 4
        self._speed_command = [0.0] * 4
        self._thrust_command = 0.0
        self._rate_command = [0.0] * 3

    @property
    def urdf_path(self) -> Path:
        return asset_path(self.urdf)

    @property
    def rotor_speeds(self) -> np.ndarray:
        """Current rotor speeds, rad/s, in ``ROTOR_LINKS`` order (a new array)."""
        return np.array(self._speeds)

    def hover_speed(self, gravity: float) -> float:
        """Rotor speed (rad/s) at which the four nominal rotors carry the nominal weight."""
        return math.sqrt(self.model.mass * gravity / (4.0 * self.config.thrust_coefficient))

    def hover_action(self, gravity: float) -> np.ndarray:
        """The action that holds a level hover at rest in the configured control mode (zero rates)."""
        c = self.config
        if c.control == "rates":
            thrust = self.model.mass * gravity / (4.0 * self.rotors.max_thrust)
            return np.array([2.0 * thrust - 1.0, 0.0, 0.0, 0.0])
        level = (self.hover_speed(gravity) - c.min_rotor_speed) / (c.max_rotor_speed - c.min_rotor_speed)
        return np.full(4, 2.0 * level - 1.0)

    def load(self, sim: Sim) -> int:
        """Load the URDF into ``sim`` as one rigid body with its own inertia, and switch off velocity damping.

        The airframe's links are merged into one pybullet body (``Sim.load_urdf(merge_fixed_links=True)``): its
        fixed joints add nothing but cost, and the tracked links' states follow from the base's
        (:class:`RigidFrames`). pybullet recomputes the inertia from the collision shapes when it loads a URDF; the
        URDF's values are set back here, and they are the nominal values :meth:`apply_dynamics` scales.

        Raises:
            ValueError: a link's URDF inertia has products of inertia (pybullet takes principal moments only), or
                the merged body's centre of mass is not the URDF's (mass on a link other than the base).
        """
        self._load(sim, merge_fixed_links=True)
        sim.set_damping(self._body, 0.0, 0.0)
        sim.paint(self._body, AIRFRAME_COLOUR)  # one colour: a camera hides the merged body and shows it again
        self.link_index = sim.link_indices(self._body)  # the merged body's: the tracked links follow from the base
        self.link_names = TRACKED_LINKS
        self._com_offset = sim.base_inertial_offset(self._body)
        if np.abs(self._com_offset - self.model.com).max() > 1e-9:
            raise ValueError(f"{self.urdf}: the merged body's centre of mass {self._com_offset.tolist()} is not the "
                             f"URDF's {self.model.com.tolist()}: put the airframe's mass on {self.base_link}")
        dt = 1.0 / sim.physics_hz
        self._decay = self.rotors.decay(dt)
        self._controller = RateController(self.model.inertia, self.config.rate_gains(), dt)
        self._gravity = sim.gravity
        if self.config.observe_thrust_ratio:
            self._estimator = ThrustRatioEstimator(self.model.mass, sim.gravity, dt,
                                                   self.config.thrust_ratio_time_constant)
        links = sorted(self.link_index.values())  # -1, the base, first
        friction = [f for _, f, _ in sim.inertial_properties(self._body, links)]
        names = {index: name for name, index in self.link_index.items()}
        self._nominal = {}
        for link, mu in zip(links, friction):
            mass, inertia = self.model.link_inertias[names[link]]
            if np.count_nonzero(inertia - np.diag(np.diag(inertia))):
                raise ValueError(f"{self.urdf} link {names[link]!r}: give the inertia in principal axes")
            self._nominal[link] = (mass, mu, tuple(np.diag(inertia).tolist()))
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
        self._sim.forget_contacts(self._body)
        self._controller.reset()
        if self._estimator is not None:
            self._estimator.reset()
        hovering = self.config.start_hovering
        speed = self.hover_speed(self._gravity) if hovering else self.config.min_rotor_speed
        self._speeds = [min(max(speed, self.config.min_rotor_speed), self.config.max_rotor_speed)] * 4
        self.apply_action(self.hover_action(self._gravity) if hovering else -np.ones(4))

    def apply_action(self, action: np.ndarray) -> None:
        """Hold a clipped, normalised action as the command of the coming ticks."""
        a = np.asarray(action, dtype=float)
        c = self.config
        if c.control == "motors":
            command = c.min_rotor_speed + 0.5 * (a + 1.0) * (c.max_rotor_speed - c.min_rotor_speed)
            self._speed_command = command.tolist()
        else:
            self._thrust_command = float(0.5 * (a[0] + 1.0) * 4.0 * self.rotors.max_thrust)
            self._rate_command = [u * scale for u, scale in zip(a[1:4].tolist(), self._rate_scale)]

    def before_tick(self) -> None:
        """One physics tick of actuation: inner loop, motor lag, then rotor forces and the body torque for the
        next ``stepSimulation`` (which clears them). Rotor speeds advance first, so a tick's forces come from the
        speeds at its end.

        All on Python floats: the vectors are 3 and 4 long, where numpy's cost per call outweighs the arithmetic.
        """
        sim, rotors, scale = self._sim, self.rotors, self._thrust_scale
        com, rot, lin, ang = sim.base_state(self._body)
        if self._estimator is not None:  # the velocity the last tick's thrust produced
            self._estimator.update((rot[2], rot[5], rot[8]), lin, self._nominal_thrust)
        if self._rates:
            torque = self._controller.torque(self._rate_command, _to_body(rot, ang))
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
            thrusts = [f * gain for f, gain in zip(thrusts, ground_effect_gain(heights, self.config.rotor_radius))]
        sim.apply_base_forces(self._body, [(0.0, 0.0, f) for f in thrusts], self._hubs)
        yaw = rotors.yaw_torque(speeds, ROTOR_SPIN) * scale
        if self._drag:
            drag = rotor_drag(_to_body(rot, lin), speeds, self.config.drag_xy, self.config.drag_z)
            force = _to_world(rot, drag)
        else:
            force = _ZERO
        sim.apply_base_wrench(self._body, force, (yaw * rot[2], yaw * rot[5], yaw * rot[8]))

    def state(self) -> RobotState:
        """Ground-truth state from one pybullet read of the base: the airframe is rigid, so the tracked links'
        states follow from the base's (:class:`RigidFrames`)."""
        com, rot, lin, ang = self._sim.base_state(self._body)
        rot = np.reshape(rot, (3, 3))
        return RobotState(
            position=np.asarray(com) - rot @ self._com_offset,
            rotation=rot,
            linear_velocity=lin,
            angular_velocity=ang,
            links=self._frames.link_states(com, rot, lin, ang),
            link_names=self.link_names,
            link_index=self.link_index,
            body=self._body,
        )

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """The base origin (world frame, metres) and the radius that encloses the rotors: what the ``rgb_array``
        view rings."""
        return state.position, RING_RADIUS

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
            "rotor_speeds": (np.array(self._speeds) / self.config.max_rotor_speed).astype(np.float32),
            "attitude": np.clip(rot[2], -1.0, 1.0).astype(np.float32),
            "velocity": np.clip(body, -self._velocity_bound, self._velocity_bound).astype(np.float32),
        }
        if self._estimator is not None:
            obs["thrust_ratio"] = np.array([self._estimator.ratio], dtype=np.float32)
        return obs


def _to_body(rot: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """``R^T v``: world-frame ``v`` in the body frame, ``rot`` the body's rotation matrix row by row (9 floats)."""
    x, y, z = v
    return (rot[0] * x + rot[3] * y + rot[6] * z,
            rot[1] * x + rot[4] * y + rot[7] * z,
            rot[2] * x + rot[5] * y + rot[8] * z)


def _to_world(rot: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """``R v``: body-frame ``v`` in the world frame, ``rot`` the body's rotation matrix row by row (9 floats)."""
    x, y, z = v
    return (rot[0] * x + rot[1] * y + rot[2] * z,
            rot[3] * x + rot[4] * y + rot[5] * z,
            rot[6] * x + rot[7] * y + rot[8] * z)
