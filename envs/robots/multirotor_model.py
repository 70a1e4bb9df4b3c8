"""What the env needs to know of a multirotor's URDF, and how it is read from a robot spec.

A multirotor of kind ``multirotor`` is a rigid airframe (fixed joints only: it is loaded as one pybullet body) whose
rotors push along the base's +z at their links' origins and yaw it by their drag torque (``robots/multirotor.py``
flies it). The spec names the rotor links, each rotor's spin and the rotor coefficients; the rotor positions, the
mass, the centre of mass and the inertia are read from the URDF. The layout must be able to fly: its allocation
(collective thrust and roll, pitch and yaw torque from the rotor thrusts) must have full rank, every rotor must carry
a positive share of a level hover's thrust, and the rotors together must lift the airframe. The IMU reads the link
``imu``, the LIDAR and the camera sit on ``sensor_mount``; a spec's ``mounts`` adds them where the URDF has none
(``robots/urdf_prep.py``). docs/robots.md shows a spec.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clutter_gym.robots.rate_loop import allocation, mixing_matrix
from clutter_gym.robots.rigid_body import RigidBody, rigid_body
from clutter_gym.robots.rotors import RotorModel
from clutter_gym.robots.spec_reading import as_number, check_keys, load_spec_urdf, spec_mounts
from clutter_gym.sim import GRAVITY
from clutter_gym.util.checks import is_number

#: The IMU's link, and the link the LIDAR and the camera sit on.
IMU_LINK, SENSOR_LINK = "imu", "sensor_mount"
#: The airframe's colour in renders: a merged body's base takes one colour (``Sim.paint``).
AIRFRAME_COLOUR = (0.15, 0.15, 0.15, 1.0)
#: The keys of a ``multirotor`` spec (besides ``kind``); the first six are required.
SPEC_KEYS = ("urdf", "rotor_links", "spin", "thrust_coefficient", "torque_coefficient", "max_rotor_speed", "name",
             "min_rotor_speed", "motor_time_constant", "drag_xy", "drag_z", "rotor_radius", "mounts")
#: What a spec that leaves them out gets: motors that may stop, the built-in quadrotor's motor lag, no rotor drag.
SPEC_DEFAULTS = {"min_rotor_speed": 0.0, "motor_time_constant": 0.05, "drag_xy": 0.0, "drag_z": 0.0}
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


def multirotor_from_spec(spec: Mapping[str, object], where: str, folder: Path | None = None) -> MultirotorModel:
    """The multirotor a ``multirotor`` spec describes (keys :data:`SPEC_KEYS`); ``urdf`` relative to ``folder``.

    Raises:
        ValueError: a key is missing, unknown or out of range, names a link the URDF does not have, the URDF is not
            a rigid airframe pybullet can merge, or the rotors cannot fly it; the message names the key, the URDF
            and what it offers.
    """
    check_keys(spec, SPEC_KEYS, 6, "multirotor", where)
    urdf = load_spec_urdf(spec, where, folder, spec_mounts(spec, where))
    kinematics, source, links, root = urdf.kinematics, urdf.source, urdf.kinematics.links, urdf.kinematics.root
    if kinematics.joints:
        raise ValueError(f"{where}: {source} has moving joints {[j.name for j in kinematics.joints]}; a multirotor's "
                         "airframe is rigid: make them fixed")
    rotors = _rotor_links(spec["rotor_links"], links, source, where)
    spin = _spin(spec["spin"], len(rotors), where)
    absent = [link for link in (IMU_LINK, SENSOR_LINK) if link not in links]
    if absent:
        raise ValueError(f"{where}: {source} has no {absent} (the IMU's link, the LIDAR's and camera's mount); add "
                         f"them with mounts, e.g. mounts: {{{IMU_LINK}: {{parent: {root}}}, {SENSOR_LINK}: {{parent: "
                         f"{root}, xyz: [0, 0, 0.01]}}}} (its links: {links})")
    try:
        body = rigid_body(urdf.urdf)
    except ValueError as error:
        raise ValueError(f"{where}: the URDF was refused: {error}") from None
    problem = airframe_problem(body)
    if problem:
        raise ValueError(f"{where}: {source}: {problem}")
    tilted = [link for link in rotors if body.frames[link][1][2, 2] < 1.0 - 1e-9]
    if tilted:
        raise ValueError(f"{where}: rotor_links {tilted} of {source} are tilted: a rotor pushes along the base's +z, "
                         "so its link's z axis must be the base's (turn its joint about z only)")
    cylinders = [e.size[0] for e in urdf.elements if e.link in rotors and e.kind == "cylinder"]
    if "rotor_radius" not in spec and not cylinders:
        raise ValueError(f"{where}: rotor_radius is needed: the rotor links of {source} have no collision cylinder "
                         "to read it from")
    defaults = {**SPEC_DEFAULTS, "rotor_radius": max(cylinders, default=math.nan)}  # the others are required
    given = {key: spec[key] if key in spec else defaults[key] for key in RANGES}
    values = {key: value if (number := as_number(value)) is None else number for key, value in given.items()}
    try:
        check_ranges(values, RANGES)
        hubs = np.array([body.frames[link][0][:2] for link in rotors])
        geometric = {e.link for e in urdf.elements} - {root}
        model = MultirotorModel(
            name=urdf.name, urdf=urdf.urdf, base_link=root, rotor_links=rotors, spin=spin,
            tracked_links=tuple(dict.fromkeys([link for link in links if link in geometric] + [IMU_LINK, SENSOR_LINK])),
            focus_radius=float(np.max(np.hypot(hubs[:, 0], hubs[:, 1]))) + values["rotor_radius"], **values)
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None
    matrix = model.allocation(body)
    problem = layout_problem(matrix, spin)
    if problem:
        raise ValueError(f"{where}: rotor_links {list(rotors)} with spin {list(spin)}: {problem}")
    lift = model.rotor_model().max_thrust / float(np.max(mixing_matrix(matrix)[:, 0]))
    if lift <= body.mass * GRAVITY:
        raise ValueError(f"{where}: max_rotor_speed {model.max_rotor_speed} rad/s gives at most {lift:.4g} N of "
                         f"collective thrust, which does not lift the airframe's {body.mass * GRAVITY:.4g} N "
                         f"({body.mass:.4g} kg): raise max_rotor_speed or thrust_coefficient")
    return model


def airframe_problem(body: RigidBody) -> str | None:
    """Why pybullet would not fly ``body`` as the URDF gives it, merged into one body (None when it would): it puts
    the merged centre of mass at the mass-weighted mean of the links' frame origins, not of their centres of mass,
    and takes the inertia's principal moments only."""
    masses = {link: mass for link, (mass, _) in body.link_inertias.items()}
    merged = sum(mass * body.frames[link][0] for link, mass in masses.items()) / body.mass
    if np.abs(merged - body.com).max() > 1e-9:
        off = [link for link, mass in masses.items() if mass > 0.0 and np.any(body.link_coms[link]
                                                                              != body.frames[link][0])]
        return (f"pybullet would put the merged airframe's centre of mass at {np.round(merged, 6).tolist()}, not at "
                f"the URDF's {np.round(body.com, 6).tolist()}: links {off} carry mass off their origins; give each "
                f"link's <inertial> the link's origin, or put the mass on {body.root}")
    if not in_principal_axes(body.inertia):
        return (f"the airframe's inertia about its centre of mass has products of inertia "
                f"{np.round(body.inertia, 12).tolist()} in the base's axes; pybullet takes principal moments only: "
                f"give the base's axes along the principal axes")
    return None


def in_principal_axes(inertia: np.ndarray) -> bool:
    """Whether the (3, 3) ``inertia``'s products are negligible (:data:`PRINCIPAL_TOLERANCE`)."""
    products = inertia - np.diag(np.diag(inertia))
    return bool(np.abs(products).max() <= PRINCIPAL_TOLERANCE * np.abs(np.diag(inertia)).max())


def _rotor_links(value: object, links: Sequence[str], source: Path, where: str) -> tuple[str, ...]:
    """``rotor_links``: 3 to 16 distinct link names of the URDF."""
    if isinstance(value, str) or not isinstance(value, (list, tuple)) or not 3 <= len(value) <= 16 \
            or len(set(map(str, value))) != len(value):
        raise ValueError(f"{where}: rotor_links must be a list of 3 to 16 distinct link names, got {value!r}")
    missing = [str(link) for link in value if link not in links]
    if missing:
        raise ValueError(f"{where}: rotor_links names {missing}, not links of {source}; its links: {links}")
    return tuple(str(link) for link in value)


def _spin(value: object, n: int, where: str) -> tuple[float, ...]:
    """``spin``: +1 (counter-clockwise seen from above) or -1 (clockwise) per rotor."""
    if isinstance(value, str) or not isinstance(value, (list, tuple)) or len(value) != n \
            or not all(is_number(s) and s in (1, -1) for s in value):
        raise ValueError(f"{where}: spin must be {n} values, one per rotor_links entry: +1 for a rotor that turns "
                         f"counter-clockwise seen from above, -1 for clockwise; got {value!r}")
    return tuple(float(s) for s in value)

