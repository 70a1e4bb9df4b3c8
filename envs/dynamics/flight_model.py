"""The reduced model of a multirotor in free flight: one rigid body under its rotors' forces, with the flight
controller's rate loop, mixer and motor lag, integrated per physics tick in compiled code.

It is the same model :class:`~clutter_gym.robots.multirotor.Multirotor` flies in pybullet, written out: per tick the
rate loop (inertia-scaled PI with the gyroscopic term) turns the held command into torques, the mixer into rotor
thrusts within their range (PX4's order of giving up: yaw, then collective, then roll and pitch together), the
motors follow with a first-order lag, and the thrusts, their drag-reaction torque, the optional rotor drag and ground
effect and gravity move the body by semi-implicit Euler (velocities first, then positions, as Bullet's), the
attitude by the exact rotation of the tick's angular velocity, each velocity coordinate within Bullet's bound. Nothing
is fitted: every number comes from the robot's model and URDF, so any multirotor a spec describes gets it.
docs/benchmarks.md ("Reduced dynamics, ClutterFly-v1") gives its divergence from pybullet.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from clutter_gym.robots.aero import GROUND_EFFECT_MIN_HEIGHT
from clutter_gym.robots.multirotor import Multirotor
from clutter_gym.robots.thrust_estimate import MIN_THRUST_SHARE, RATIO_BOUNDS

#: rows of a flight state: centre of mass (3, m), attitude quaternion (x, y, z, w), linear and angular velocity
#: (world, m/s and rad/s), the rate loop's integral (rad), the thrust-ratio estimate, whether the estimator holds a
#: velocity, that velocity (m/s), the nominal thrust of the last tick (N), the path length of the centre of mass (m)
#: and the angle turned (rad) over the last :func:`flight_ticks` call, then one speed per rotor (rad/s)
(COM, QUAT, LIN, ANG, INTEGRAL, RATIO, HAS_VELOCITY, VELOCITY, NOMINAL_THRUST, TRAVEL, TURN,
 SPEEDS) = 0, 3, 7, 10, 13, 16, 17, 18, 21, 22, 23, 24
#: rows of the parameter array
(MASS, INERTIA, NOMINAL_INERTIA, KP, KI, INTEGRAL_LIMIT, DT, KF, KM, DECAY, MIN_SPEED, MAX_SPEED, THRUST_SCALE,
 GRAVITY, DRAG_XY, DRAG_Z, DRAG_ON, GROUND_ON, GROUND_LOWEST, ROTOR_RADIUS, MIN_THRUST, MAX_THRUST, RATES,
 ESTIMATOR_ON, ESTIMATOR_GAIN, NOMINAL_MASS, ESTIMATOR_MIN_THRUST, RATIO_LOW, RATIO_HIGH) = (
    0, 1, 4, 13, 16, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32, 33, 34, 35, 36, 37, 38, 39, 40, 41, 42)
PARAMS_SIZE = 43
#: m/s and rad/s: pybullet's bound on each of a floating base's six velocity coordinates, world frame
#: (btMultiBody's maxCoordinateVelocity); a tumbling airframe reaches it
MAX_COORDINATE_VELOCITY = 100.0
#: columns of the rotor table: hub position from the centre of mass (body frame, m), spin, the mixer's row (N per
#: roll, pitch and yaw torque N m) and the rotor's share of the collective thrust
HUB, SPIN, MIX, SHARE = 0, 3, 4, 7


def state_size(n_rotors: int) -> int:
    """Length of a flight state of ``n_rotors`` rotors."""
    return SPEEDS + n_rotors


def flight_params(robot: Multirotor, physics_hz: float, gravity: float, mass_scale: float = 1.0,
                  motor_scale: float = 1.0) -> np.ndarray:
    """The parameter array of ``robot`` (loaded or not) at ``physics_hz``, its mass and inertia times
    ``mass_scale`` and its rotors' thrust and torque times ``motor_scale`` (an episode's dynamics); the flight
    controller keeps the nominal model, as :class:`Multirotor`'s does."""
    body, model, config, rotors = robot.mass_properties, robot.model, robot.config, robot.rotors
    gains = config.rate_gains()
    dt = 1.0 / physics_hz
    p = np.zeros(PARAMS_SIZE)
    p[MASS] = body.mass * mass_scale
    p[INERTIA:INERTIA + 3] = np.diag(body.inertia) * mass_scale
    p[NOMINAL_INERTIA:NOMINAL_INERTIA + 9] = body.inertia.ravel()
    p[KP:KP + 3], p[KI:KI + 3], p[INTEGRAL_LIMIT] = gains.kp, gains.ki, gains.integral_limit
    p[DT], p[KF], p[KM], p[DECAY] = dt, rotors.thrust_coefficient, rotors.torque_coefficient, rotors.decay(dt)
    p[MIN_SPEED], p[MAX_SPEED], p[THRUST_SCALE], p[GRAVITY] = rotors.min_speed, rotors.max_speed, motor_scale, gravity
    p[DRAG_XY], p[DRAG_Z], p[DRAG_ON] = model.drag_xy, model.drag_z, float("drag" in config.aero)
    p[GROUND_ON], p[ROTOR_RADIUS] = float("ground_effect" in config.aero), model.rotor_radius
    p[GROUND_LOWEST] = GROUND_EFFECT_MIN_HEIGHT * model.rotor_radius
    p[MIN_THRUST], p[MAX_THRUST], p[RATES] = rotors.min_thrust, rotors.max_thrust, float(config.control == "rates")
    p[ESTIMATOR_ON] = float(config.observe_thrust_ratio)
    p[ESTIMATOR_GAIN] = 1.0 - math.exp(-dt / config.thrust_ratio_time_constant)
    p[NOMINAL_MASS], p[ESTIMATOR_MIN_THRUST] = body.mass, MIN_THRUST_SHARE * body.mass * gravity
    p[RATIO_LOW], p[RATIO_HIGH] = RATIO_BOUNDS
    return p


def rotor_table(robot: Multirotor) -> np.ndarray:
    """The (n rotors, 8) rotor table of ``robot`` (columns :data:`HUB`, :data:`SPIN`, :data:`MIX`, :data:`SHARE`)."""
    body, model = robot.mass_properties, robot.model
    hubs = np.array([body.frames[link][0] - body.com for link in model.rotor_links])
    mixer = robot.mixer
    return np.column_stack([hubs, np.array(model.spin), np.array(mixer.torque_rows), np.array(mixer.shares)])


@numba.njit(cache=True)
def mix(thrust: float, tx: float, ty: float, tz: float, rotors: np.ndarray, lo: float, hi: float,
        out: np.ndarray) -> None:
    """Rotor thrusts (N) into ``out`` for a collective ``thrust`` (N) and body torques (N m): the same choices as
    :meth:`clutter_gym.robots.rate_loop.Mixer.thrusts`."""
    n = rotors.shape[0]
    span = hi - lo
    for i in range(n):
        out[i] = rotors[i, MIX] * tx + rotors[i, MIX + 1] * ty + rotors[i, MIX + 2] * tz
    if out.max() - out.min() > span:
        rp = rotors[:, MIX] * tx + rotors[:, MIX + 1] * ty
        yaw = rotors[:, MIX + 2] * tz
        spread = rp.max() - rp.min()
        if spread > span:
            for i in range(n):
                out[i] = rp[i] * (span / spread)
        else:
            k = math.inf
            for i in range(n):
                for j in range(n):
                    if yaw[i] > yaw[j]:
                        k = min(k, (span - (rp[i] - rp[j])) / (yaw[i] - yaw[j]))
            k = max(0.0, k)
            for i in range(n):
                out[i] = rp[i] + yaw[i] * k
    for i in range(n):
        out[i] += thrust * rotors[i, SHARE]
    if out.min() < lo:
        shift = -math.inf
        for i in range(n):
            shift = max(shift, (lo - out[i]) / rotors[i, SHARE])
        for i in range(n):
            out[i] = min(out[i] + shift * rotors[i, SHARE], hi)
    elif out.max() > hi:
        shift = -math.inf
        for i in range(n):
            shift = max(shift, (out[i] - hi) / rotors[i, SHARE])
        for i in range(n):
            out[i] = max(out[i] - shift * rotors[i, SHARE], lo)


@numba.njit(cache=True)
def _rotation(q: np.ndarray, r: np.ndarray) -> None:
    """The rotation matrix of the unit quaternion ``q`` (x, y, z, w) into ``r`` (3, 3)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    r[0, 0], r[0, 1], r[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    r[1, 0], r[1, 1], r[1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    r[2, 0], r[2, 1], r[2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)


@numba.njit(cache=True)
def flight_ticks(state: np.ndarray, params: np.ndarray, rotors: np.ndarray, command: np.ndarray, ticks: int) -> None:
    """Advance ``state`` (rows :data:`COM` ... :data:`SPEEDS`) in place by ``ticks`` physics ticks under the held
    ``command``: (collective thrust N, body rates rad/s) in the rates mode, one speed per rotor (rad/s) otherwise.
    No point of the body moves further than ``state[TRAVEL] + r * state[TURN]`` from where it was, ``r`` its distance
    from the centre of mass."""
    n = rotors.shape[0]
    p = params
    dt, g, mass, scale = p[DT], p[GRAVITY], p[MASS], p[THRUST_SCALE]
    r = np.empty((3, 3))
    thrusts = np.empty(n)
    targets = np.empty(n)
    j = np.empty((3, 3))  # the flight controller's (nominal) inertia
    for a in range(3):
        for b in range(3):
            j[a, b] = p[NOMINAL_INERTIA + 3 * a + b]
    ixx, iyy, izz = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    state[TRAVEL], state[TURN] = 0.0, 0.0
    for _ in range(ticks):
        _rotation(state[QUAT:QUAT + 4], r)
        vx, vy, vz = state[LIN], state[LIN + 1], state[LIN + 2]
        wx, wy, wz = state[ANG], state[ANG + 1], state[ANG + 2]
        if p[ESTIMATOR_ON] > 0.0:  # the velocity the last tick's thrust produced (thrust_estimate.py)
            if state[HAS_VELOCITY] > 0.0 and state[NOMINAL_THRUST] >= p[ESTIMATOR_MIN_THRUST]:
                f = ((vx - state[VELOCITY]) * r[0, 2] + (vy - state[VELOCITY + 1]) * r[1, 2]
                     + (vz - state[VELOCITY + 2] + g * dt) * r[2, 2]) / dt
                sample = min(max(f * p[NOMINAL_MASS] / state[NOMINAL_THRUST], p[RATIO_LOW]), p[RATIO_HIGH])
                state[RATIO] += p[ESTIMATOR_GAIN] * (sample - state[RATIO])
            state[VELOCITY], state[VELOCITY + 1], state[VELOCITY + 2] = vx, vy, vz
            state[HAS_VELOCITY] = 1.0
        # body rates: R^T w
        bp = r[0, 0] * wx + r[1, 0] * wy + r[2, 0] * wz
        bq = r[0, 1] * wx + r[1, 1] * wy + r[2, 1] * wz
        br = r[0, 2] * wx + r[1, 2] * wy + r[2, 2] * wz
        if p[RATES] > 0.0:  # the rate loop and the mixer (rate_loop.py)
            limit = p[INTEGRAL_LIMIT]
            ep, eq, er = command[1] - bp, command[2] - bq, command[3] - br
            ip = min(max(state[INTEGRAL] + ep * dt, -limit), limit)
            iq = min(max(state[INTEGRAL + 1] + eq * dt, -limit), limit)
            ir = min(max(state[INTEGRAL + 2] + er * dt, -limit), limit)
            state[INTEGRAL], state[INTEGRAL + 1], state[INTEGRAL + 2] = ip, iq, ir
            ap, aq, ar = p[KP] * ep + p[KI] * ip, p[KP + 1] * eq + p[KI + 1] * iq, p[KP + 2] * er + p[KI + 2] * ir
            hp = j[0, 0] * bp + j[0, 1] * bq + j[0, 2] * br
            hq = j[1, 0] * bp + j[1, 1] * bq + j[1, 2] * br
            hr = j[2, 0] * bp + j[2, 1] * bq + j[2, 2] * br
            tx = j[0, 0] * ap + j[0, 1] * aq + j[0, 2] * ar + (bq * hr - br * hq)
            ty = j[1, 0] * ap + j[1, 1] * aq + j[1, 2] * ar + (br * hp - bp * hr)
            tz = j[2, 0] * ap + j[2, 1] * aq + j[2, 2] * ar + (bp * hq - bq * hp)
            mix(command[0], tx, ty, tz, rotors, p[MIN_THRUST], p[MAX_THRUST], thrusts)
            for i in range(n):
                targets[i] = math.sqrt(max(thrusts[i], 0.0) / p[KF])
        else:
            for i in range(n):
                targets[i] = command[i]
        total_speed, spin_torque, nominal_thrust = 0.0, 0.0, 0.0
        for i in range(n):  # the motors' lag, then each rotor's thrust and drag torque (rotors.py)
            target = min(max(targets[i], p[MIN_SPEED]), p[MAX_SPEED])
            w = target + (state[SPEEDS + i] - target) * p[DECAY]
            state[SPEEDS + i] = w
            thrusts[i] = p[KF] * (w * w)
            nominal_thrust += thrusts[i]
            total_speed += w
            spin_torque -= p[KM] * rotors[i, SPIN] * (w * w)
        state[NOMINAL_THRUST] = nominal_thrust
        fx, fy, fz = 0.0, 0.0, 0.0  # body frame
        mx, my, mz = 0.0, 0.0, spin_torque * scale
        for i in range(n):
            f = thrusts[i] * scale
            if p[GROUND_ON] > 0.0 and r[2, 2] > 0.0:  # upright: the rotors blow towards the ground (aero.py)
                height = (state[COM + 2] + r[2, 0] * rotors[i, HUB] + r[2, 1] * rotors[i, HUB + 1]
                          + r[2, 2] * rotors[i, HUB + 2])
                ratio = p[ROTOR_RADIUS] / (4.0 * max(height, p[GROUND_LOWEST]))
                f /= 1.0 - ratio * ratio
            fz += f
            mx += rotors[i, HUB + 1] * f
            my -= rotors[i, HUB] * f
        if p[DRAG_ON] > 0.0:  # rotor drag on the body-frame velocity
            ux = r[0, 0] * vx + r[1, 0] * vy + r[2, 0] * vz
            uy = r[0, 1] * vx + r[1, 1] * vy + r[2, 1] * vz
            uz = r[0, 2] * vx + r[1, 2] * vy + r[2, 2] * vz
            fx -= total_speed * p[DRAG_XY] * ux
            fy -= total_speed * p[DRAG_XY] * uy
            fz -= total_speed * p[DRAG_Z] * uz
        # semi-implicit Euler: velocities from this tick's forces, then positions from the new velocities
        vx += (r[0, 0] * fx + r[0, 1] * fy + r[0, 2] * fz) / mass * dt
        vy += (r[1, 0] * fx + r[1, 1] * fy + r[1, 2] * fz) / mass * dt
        vz += ((r[2, 0] * fx + r[2, 1] * fy + r[2, 2] * fz) / mass - g) * dt
        dp = (mx - (bq * izz * br - br * iyy * bq)) / ixx * dt
        dq = (my - (br * ixx * bp - bp * izz * br)) / iyy * dt
        dr = (mz - (bp * iyy * bq - bq * ixx * bp)) / izz * dt
        bp, bq, br = bp + dp, bq + dq, br + dr
        wx = r[0, 0] * bp + r[0, 1] * bq + r[0, 2] * br
        wy = r[1, 0] * bp + r[1, 1] * bq + r[1, 2] * br
        wz = r[2, 0] * bp + r[2, 1] * bq + r[2, 2] * br
        # Bullet bounds each of a floating base's six velocity coordinates (world frame) by its maxCoordinateVelocity
        state[LIN], state[LIN + 1], state[LIN + 2] = _bound(vx), _bound(vy), _bound(vz)
        state[ANG], state[ANG + 1], state[ANG + 2] = _bound(wx), _bound(wy), _bound(wz)
        vx, vy, vz, wx, wy, wz = state[LIN], state[LIN + 1], state[LIN + 2], state[ANG], state[ANG + 1], state[ANG + 2]
        state[COM] += vx * dt
        state[COM + 1] += vy * dt
        state[COM + 2] += vz * dt
        state[TRAVEL] += math.sqrt(vx * vx + vy * vy + vz * vz) * dt
        state[TURN] += math.sqrt(wx * wx + wy * wy + wz * wz) * dt
        _turn(state[QUAT:QUAT + 4], wx * dt, wy * dt, wz * dt)


@numba.njit(cache=True)
def _bound(x: float) -> float:
    return min(max(x, -MAX_COORDINATE_VELOCITY), MAX_COORDINATE_VELOCITY)


@numba.njit(cache=True)
def _turn(q: np.ndarray, ax: float, ay: float, az: float) -> None:
    """Rotate the attitude ``q`` in place by the rotation vector (ax, ay, az) (world frame, rad)."""
    angle = math.sqrt(ax * ax + ay * ay + az * az)
    if angle < 1e-15:
        return
    s = math.sin(0.5 * angle) / angle
    dx, dy, dz, dw = ax * s, ay * s, az * s, math.cos(0.5 * angle)
    x, y, z, w = q[0], q[1], q[2], q[3]
    q[0] = dw * x + dx * w + dy * z - dz * y
    q[1] = dw * y - dx * z + dy * w + dz * x
    q[2] = dw * z + dx * y - dy * x + dz * w
    q[3] = dw * w - dx * x - dy * y - dz * z
    norm = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    q /= norm
