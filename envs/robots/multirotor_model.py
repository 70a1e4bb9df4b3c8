"""What the env needs to know of a multirotor's URDF: a rigid airframe (fixed joints only: it is loaded as one pybullet
body) whose rotors push along the base's +z at their links' origins and yaw it by their drag torque
(``robots/multirotor.py`` flies it). The rotors' layout must be able to fly: its allocation (collective thrust and
roll, pitch and yaw torque from the rotor thrusts) must have full rank, and every rotor must carry a positive share
of a level hover's thrust. The IMU reads the link ``imu``, the LIDAR and the camera sit on ``sensor_mount``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.robots.rate_loop import allocation, mixing_matrix
from clutter_gym.robots.rigid_body import RigidBody
from clutter_gym.robots.rotors import RotorModel
from clutter_gym.util.checks import is_number

#: The IMU's link, and the link the LIDAR and the camera sit on.
IMU_LINK, SENSOR_LINK = "imu", "sensor_mount"
#: The airframe's colour in renders: a merged body's base takes one colour (``Sim.paint``).
AIRFRAME_COLOUR = (0.15, 0.15, 0.15, 1.0)
#: (low, high, low_open) of every number of the airframe: low < value (low_open) or low <= value, and value <= high
RANGES = {
    "thrust_coefficient": (0.0, 1e-4, True),
    "torque_coefficient": (0.0, 1e-5, True),  # > 0: the rotors' drag torque is what yaws the airframe
    "max_rotor_speed": (0.0, 1e4, True),
    "min_rotor_speed": (0.0, 1e4, False),
    "motor_time_constant": (0.0, 1.0, False),
    "drag_xy": (0.0, 1e-3, False),
    "drag_z": (0.0, 1e-3, False),
    "rotor_radius": (0.0, 0.5, True),
}
#: A layout whose allocation, rows scaled to unit length, has a singular value below this share of its largest is
#: degenerate: it would need unbounded rotor thrusts for some torque.
RANK_TOLERANCE = 1e-6
#: Relative to the largest moment: products of inertia pybullet would drop (it takes principal moments only).
PRINCIPAL_TOLERANCE = 1e-9


@dataclass(frozen=True)
class MultirotorModel:
    """A multirotor's URDF and the facts about it the env uses.

    Attributes:
        name: the robot's name.
        urdf: the URDF file pybullet and the collision layer load.
        base_link: the URDF's root link: pybullet's base, the frame of the robot's pose (x forward, z up).
        rotor_links: the links at the rotor hubs; a rotor pushes along the base's +z at its link's origin.
        spin: per rotor, +1 if it turns counter-clockwise seen from above, -1 if clockwise (``robots/rotors.py``).
        tracked_links: links read every step: every link with collision geometry but the base, the IMU's link and
            the sensor mount.
        thrust_coefficient: kf, N / (rad/s)^2.
        torque_coefficient: km, N m / (rad/s)^2.
        max_rotor_speed: rad/s; action +1 of the motor mode.
        min_rotor_speed: rad/s; action -1 of the motor mode.
        motor_time_constant: first-order lag of the rotor speeds, seconds (0: none).
        drag_xy: rotor-induced drag coefficient along body x and y, kg/rad (``"drag"`` in the config's ``aero``).
        drag_z: rotor-induced drag coefficient along body z, kg/rad.
        rotor_radius: propeller radius for the ground effect, metres.
        focus_radius: metres about the base origin that the ``rgb_array`` view rings (the rotors' reach).
        colour: RGBA of the airframe in renders.
    """

    name: str
    urdf: Path
    base_link: str
    rotor_links: tuple[str, ...]
    spin: tuple[float, ...]
    tracked_links: tuple[str, ...]
    thrust_coefficient: float
    torque_coefficient: float
    max_rotor_speed: float
    min_rotor_speed: float
    motor_time_constant: float
    drag_xy: float
    drag_z: float
    rotor_radius: float
    focus_radius: float
    colour: tuple[float, float, float, float] = AIRFRAME_COLOUR

    def __post_init__(self) -> None:
        check_ranges({name: getattr(self, name) for name in RANGES}, RANGES)
        if self.min_rotor_speed >= self.max_rotor_speed:
            raise ValueError(f"min_rotor_speed must be in [0, max_rotor_speed={self.max_rotor_speed}), got "
                             f"{self.min_rotor_speed!r}")
        if len(self.spin) != len(self.rotor_links) or any(s not in (1.0, -1.0) for s in self.spin):
            raise ValueError(f"spin must be {len(self.rotor_links)} values, +1 or -1, one per rotor link, got "
                             f"{self.spin!r}")

    def rotor_model(self) -> RotorModel:
        """The rotors these values describe."""
        return RotorModel(self.thrust_coefficient, self.torque_coefficient, self.motor_time_constant,
                          self.min_rotor_speed, self.max_rotor_speed)

    def allocation(self, body: RigidBody) -> np.ndarray:
        """The (4, n) allocation of the rotors (``rate_loop.allocation``) about ``body``'s centre of mass."""
        hubs = np.array([body.frames[link][0] - body.com for link in self.rotor_links])
        return allocation(hubs[:, :2], np.array(self.spin), self.torque_coefficient / self.thrust_coefficient)


def check_ranges(values: Mapping[str, object], ranges: Mapping[str, tuple[float, float, bool]]) -> None:
    """Refuse any of ``values`` outside its ``(low, high, low_open)`` range, naming it and the range."""
    for name, value in values.items():
        lo, hi, low_open = ranges[name]
        number = is_number(value) and math.isfinite(value)
        if not (number and (lo < value if low_open else lo <= value) and value <= hi):
            bracket = "(" if low_open else "["
            raise ValueError(f"{name} must be a number in {bracket}{lo}, {hi}], got {value!r}")


def layout_problem(matrix: np.ndarray, spin: Sequence[float]) -> str | None:
    """Why the rotors of the (4, n) allocation ``matrix`` cannot fly, in words (None when they can): they must give
    collective thrust and roll, pitch and yaw torque independently, and hover level with every rotor pushing."""
    rank = _rank(matrix)
    if rank < 4:
        n = matrix.shape[1]
        if n < 4:
            why = f"{n} rotors give at most {n} of the four; it takes four or more"
        elif len(set(spin)) == 1:
            why = "every rotor turns the same way, so no yaw torque comes without thrust: give both senses"
        elif _rank(matrix[:3]) < 3:  # thrust, roll and pitch alone
            why = "the rotors lie on one line seen from above, so nothing turns the airframe about that line"
        else:
            why = ("the spins' yaw torque comes only with roll or pitch torque (rotors that turn alike side by "
                   "side): alternate the senses around the airframe")
        return (f"the rotors cannot give collective thrust and roll, pitch and yaw torque independently (their "
                f"allocation has rank {rank} < 4): {why}")
    shares = mixing_matrix(matrix)[:, 0]
    if np.any(shares <= 0.0):
        return (f"a level hover needs thrust shares {np.round(shares, 4).tolist()}, not all positive: the centre of "
                "mass must lie within the rotors seen from above, and the spins must balance")
    return None


def _rank(rows: np.ndarray) -> int:
    """The numerical rank of ``rows`` scaled to unit length (their units differ: newtons, metres)."""
    norms = np.linalg.norm(rows, axis=1, keepdims=True)
    singular = np.linalg.svd(rows / np.where(norms > 0.0, norms, 1.0), compute_uv=False)
    return int(np.sum(singular > RANK_TOLERANCE * singular[0]))


def in_principal_axes(inertia: np.ndarray) -> bool:
    """Whether the (3, 3) ``inertia``'s products are negligible (:data:`PRINCIPAL_TOLERANCE`)."""
    products = inertia - np.diag(np.diag(inertia))
    return bool(np.abs(products).max() <= PRINCIPAL_TOLERANCE * np.abs(np.diag(inertia)).max())
