"""The quadrotor against closed forms: hover, free fall, motor lag, yaw acceleration, rate-loop step, drag, ground
effect; the mixer's saturation order; config errors; determinism; the env's per-tick hook.

Each physics test drives the robot as an env does (``before_tick(); sim.step()`` per tick) in a bare Sim with no
ground (nothing to touch) unless it needs one. pybullet integrates with semi-implicit Euler: under a constant force
its velocity is exact at the ticks and its position runs ahead of the continuous solution, along the acceleration,
by ``a dt t / 2``; the tests compare with the discrete closed forms to rounding and with the continuous ones within
that lead.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from clutter_gym.assets import asset_path
from clutter_gym.robots import Multirotor, Quadrotor, QuadrotorConfig
from clutter_gym.robots.aero import ground_effect_gain, rotor_drag
from clutter_gym.robots.quadrotor import ROTOR_SPIN, quadrotor_model
from clutter_gym.robots.rate_loop import Mixer, allocation
from clutter_gym.robots.rigid_body import rigid_body
from clutter_gym.sim import Sim, pb

HZ = 240.0
DT = 1.0 / HZ
START = (0.0, 0.0, 5.0, 0.0)


def flying(config: QuadrotorConfig | None = None, start=START, ground: bool = False,
           **airframe: float) -> tuple[Sim, Quadrotor]:
    """The quadrotor hovering at ``start`` in a fresh Sim; ``airframe`` changes its model's values."""
    sim = Sim(physics_hz=HZ)
    if ground:
        sim.add_ground(visual_size=1.0)
    robot = Multirotor(replace(quadrotor_model(), **airframe), config)
    robot.load(sim)
    robot.reset_to(start)
    return sim, robot


def run(sim: Sim, robot: Quadrotor, ticks: int, record=None) -> list:
    """Step ``ticks`` physics ticks as the env does; ``record(robot)`` after each tick, its values returned."""
    out = []
    for _ in range(ticks):
        robot.before_tick()
        sim.step()
        if record is not None:
            out.append(record(robot))
    return out


def base(robot: Quadrotor):
    """(position, linear velocity, body angular velocity) of the base."""
    s = robot.state()
    return s.position.copy(), np.array(s.linear_velocity), s.rotation.T @ np.array(s.angular_velocity)


@pytest.fixture
def sims():
    made = []
    yield made
    for sim in made:
        sim.close()


def make(sims, *args, **kwargs) -> tuple[Sim, Quadrotor]:
    sim, robot = flying(*args, **kwargs)
    sims.append(sim)
    return sim, robot


# ------------------------------------------------------------------------------------------- the model's numbers
def test_urdf_mass_properties_are_the_stated_closed_forms_and_crazyflie_sized(sims):
    body = rigid_body(asset_path("robots/quadrotor.urdf"))
    # the URDF comment's composite, and the centre of mass at the base origin by construction
    assert body.mass == pytest.approx(0.027, rel=1e-12)
    np.testing.assert_allclose(body.com, 0.0, atol=1e-9)
    np.testing.assert_allclose(np.diag(body.inertia), [1.3287e-5, 1.3661e-5, 2.3396e-5], rtol=1e-4)
    # within 10 % of the measured Crazyflie 2.0 inertia (Foerster 2015)
    np.testing.assert_allclose(np.diag(body.inertia), [1.395e-5, 1.436e-5, 2.173e-5], rtol=0.1)
    # pybullet holds the URDF's masses and inertias, not inertias it recomputed from the collision shapes
    sim, robot = make(sims)
    names = {index: name for name, index in robot.link_index.items()}
    for link, (mass, _, inertia) in zip(names, sim.actuation.inertial_properties(robot.body, list(names))):
        urdf_mass, urdf_inertia = body.link_inertias[names[link]]
        assert mass == urdf_mass
        np.testing.assert_array_equal(inertia, np.diag(urdf_inertia))


def _box(m: float, x: float, y: float, z: float) -> np.ndarray:
    return m * np.diag([y * y + z * z, x * x + z * z, x * x + y * y]) / 12.0


def _cylinder(m: float, r: float, h: float) -> np.ndarray:
    return m * np.diag([(3 * r * r + h * h) / 12.0, (3 * r * r + h * h) / 12.0, r * r / 2.0])


def test_base_link_carries_the_parts_closed_forms_composed(sims):
    """The URDF header's parts (PCB, battery, four arms, four propeller discs and motors) composed with the
    parallel-axis theorem give base_link's mass, centre of mass and inertia, which pybullet's merged body holds."""
    a = 0.046 / math.sqrt(2.0)
    parts = [(0.009, np.zeros(3), _box(0.009, 0.035, 0.035, 0.0016)),
             (0.0072, np.array([0.0, 0.0, -0.010]), _box(0.0072, 0.032, 0.020, 0.0075))]
    for yaw, (sx, sy) in zip((-0.25, -0.75, 0.75, 0.25), ((1, -1), (-1, -1), (-1, 1), (1, 1))):
        c, s = math.cos(math.pi * yaw), math.sin(math.pi * yaw)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        parts.append((0.0005, turn @ [0.027, 0.0, 0.0], turn @ _box(0.0005, 0.030, 0.005, 0.0016) @ turn.T))
        hub = np.array([sx * a, sy * a, 0.018])
        parts += [(0.0004, hub, _cylinder(0.0004, 0.0231, 0.004)),
                  (0.0018, hub + [0.0, 0.0, -0.012], _cylinder(0.0018, 0.0035, 0.020))]
    mass = sum(m for m, _, _ in parts)
    com = sum(m * p for m, p, _ in parts) / mass
    inertia = sum(i + m * ((p - com) @ (p - com) * np.eye(3) - np.outer(p - com, p - com)) for m, p, i in parts)
    body = rigid_body(asset_path("robots/quadrotor.urdf"))
    assert body.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(body.com, com, atol=1e-15)
    np.testing.assert_allclose(body.inertia, inertia, rtol=1e-12, atol=1e-18)  # the file's 13 digits
    sim, robot = make(sims)
    assert sim.link_indices(robot.body) == {"base_link": -1}  # one merged body
    (merged_mass, _, merged_inertia), = sim.actuation.inertial_properties(robot.body, [-1])
    assert merged_mass == body.mass
    np.testing.assert_array_equal(merged_inertia, np.diag(body.inertia))
    np.testing.assert_allclose(sim.base_inertial_offset(robot.body), body.com, atol=1e-15)


# ----------------------------------------------------------------------------------------------------- physics
@pytest.mark.parametrize("control", ["motors", "rates"])
def test_hover_at_the_computed_rotor_speed_holds_position_for_ten_seconds(sims, control):
    sim, robot = make(sims, QuadrotorConfig(control=control))
    robot.apply_action(robot.hover_action(sim.gravity))
    speeds = run(sim, robot, int(10 * HZ), lambda r: r.rotor_speeds)
    np.testing.assert_allclose(speeds, math.sqrt(0.027 * sim.gravity / (4 * robot.model.thrust_coefficient)),
                               rtol=1e-12)
    position, velocity, _ = base(robot)
    # thrust and weight balance to rounding, so only rounding moves it: 1 mm (the spec) is far above that
    assert np.abs(position - START[:3]).max() < 1e-3
    assert np.abs(velocity).max() < 1e-4


def test_free_fall_with_rotors_stopped_matches_g_t_squared_over_two(sims):
    sim, robot = make(sims, QuadrotorConfig(control="motors", start_hovering=False))
    robot.apply_action(-np.ones(4))
    n = int(HZ)  # one second
    z = np.array(run(sim, robot, n, lambda r: r.state().position[2]))
    k = np.arange(1, n + 1)
    g = sim.gravity
    # semi-implicit Euler, exactly: z_k = z0 - g dt^2 k (k + 1) / 2
    np.testing.assert_allclose(z, START[2] - g * DT**2 * k * (k + 1) / 2, rtol=0, atol=1e-9)
    # the continuous g t^2 / 2, within the integrator's lead g dt t / 2 (2 cm after 1 s at 240 Hz)
    t = k * DT
    assert np.all(np.abs(z - (START[2] - g * t**2 / 2)) <= g * DT * t / 2 + 1e-9)
    assert np.all(robot.rotor_speeds == 0.0)


def test_thrust_step_follows_the_exact_first_order_motor_response(sims):
    sim, robot = make(sims, QuadrotorConfig(control="motors"))
    c = robot.model
    w0 = robot.hover_speeds(sim.gravity)[0]
    w1 = 1.2 * w0
    robot.apply_action(np.full(4, 2 * w1 / c.max_rotor_speed - 1))  # min_rotor_speed is 0
    n = int(0.3 * HZ)  # six time constants
    rows = run(sim, robot, n, lambda r: (r.rotor_speeds[0], base(r)[1][2]))
    speeds, vz = np.array(rows).T
    k = np.arange(1, n + 1)
    expected = w1 + (w0 - w1) * np.exp(-k * DT / c.motor_time_constant)
    np.testing.assert_allclose(speeds, expected, rtol=1e-12)
    # the engine's vertical velocity is the sum of (4 kf w^2 / m - g) dt over the ticks (forces from the speeds at
    # each tick's end): pybullet's velocity update is exact for a force held over a tick
    accel = 4 * c.thrust_coefficient * expected**2 / 0.027 - sim.gravity
    np.testing.assert_allclose(vz, np.cumsum(accel) * DT, rtol=1e-9, atol=1e-12)


def test_pure_yaw_command_gives_the_yaw_acceleration_of_the_coefficients_and_inertia(sims):
    sim, robot = make(sims, QuadrotorConfig(control="motors"))
    c = robot.model
    w0 = robot.hover_speeds(sim.gravity)[0]
    spin = np.array(ROTOR_SPIN)
    # clockwise rotors (spin -1) faster, counter-clockwise slower, squares moved alike: thrust unchanged at rest
    command = w0 * np.sqrt(1 - 0.2 * spin)
    robot.apply_action(2 * command / c.max_rotor_speed - 1)
    n = int(0.5 * HZ)
    rows = run(sim, robot, n, lambda r: np.concatenate([r.rotor_speeds, base(r)[2]]))
    speeds, rates = np.array(rows)[:, :4], np.array(rows)[:, 4:]
    izz = rigid_body(robot.urdf_path).inertia[2, 2]  # the URDF's closed forms (first test)
    torque = -c.torque_coefficient * (speeds**2 @ spin)
    # pybullet composes the links' inertias itself: agreement to rounding says forces, torque and inertia match
    np.testing.assert_allclose(rates[:, 2], np.cumsum(torque) * DT / izz, rtol=1e-9)
    # after the lag: the steady yaw acceleration km * sum(-spin w^2) / Izz = km * 0.8 w0^2 / Izz
    steady = c.torque_coefficient * 0.2 * w0**2 * 4 / izz
    measured = (rates[-1, 2] - rates[-11, 2]) / (10 * DT)
    assert measured == pytest.approx(steady, rel=1e-3)  # e^(-0.5/0.05) of the lag is left
    assert np.abs(rates[:, :2]).max() < 1e-9  # diagonal rotors alike: no roll or pitch torque


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rate_step_through_the_inner_loop_settles_with_bounded_overshoot(sims, axis):
    sim, robot = make(sims, QuadrotorConfig(control="rates"))
    c = robot.config
    action = robot.hover_action(sim.gravity)
    limits = (c.max_roll_rate, c.max_pitch_rate, c.max_yaw_rate)
    step = 1.0  # rad/s: small enough for no rotor to saturate
    action[1 + axis] = step / limits[axis]
    robot.apply_action(action)
    rates = np.array(run(sim, robot, int(0.6 * HZ), lambda r: base(r)[2]))
    t = np.arange(1, len(rates) + 1) * DT
    response = rates[:, axis] / step
    # kp = 10/s with the 0.05 s motor lag: a second-order loop with damping 0.71, 4.3 % overshoot and a 5 %
    # settling time of 0.21 s when linearised; bounds 10 % and 0.3 s leave room for the quadratic rotors
    assert response.max() - 1 < 0.10
    outside = np.nonzero(np.abs(response - 1) > 0.05)[0]
    assert t[outside[-1] + 1] < 0.3
    # and on the command, not short of it: no spurious torque (a thrust one tick behind the body left it 6 % short)
    assert abs(response[-12:].mean() - 1) < 0.01
    others = np.delete(rates, axis, axis=1)
    assert np.abs(others).max() < 0.05 * step


def test_rotor_drag_gives_the_terminal_climb_rate_of_its_model(sims):
    # no motor lag, so the rotors spin at w from the first tick and the climb is a first-order response
    sim, robot = make(sims, QuadrotorConfig(control="motors", aero=("drag",)), motor_time_constant=0.0)
    c = robot.model
    w = 1.05 * robot.hover_speeds(sim.gravity)[0]
    robot.apply_action(np.full(4, 2 * w / c.max_rotor_speed - 1))
    n = int(30 * HZ)
    vz = np.array(run(sim, robot, n, lambda r: r.state().linear_velocity[2]))
    excess = 4 * c.thrust_coefficient * w**2 - 0.027 * sim.gravity  # N
    damping = 4 * w * c.drag_z  # kg/s: the drag is -drag_z * sum(w) * v along body z
    terminal = excess / damping
    # semi-implicit Euler of m dv/dt = excess - damping v: v_k = v_t (1 - (1 - damping dt / m)^k)
    k = np.arange(1, n + 1)
    np.testing.assert_allclose(vz, terminal * (1 - (1 - damping * DT / 0.027) ** k), rtol=1e-9)
    # and after 30 s (7.3 time constants m / damping) within 0.1 % of the terminal climb rate
    assert vz[-1] == pytest.approx(terminal, rel=1e-3)


def test_ground_effect_lifts_a_hovering_rotor_set_by_the_cheeseman_bennett_gain(sims):
    radius = quadrotor_model().rotor_radius
    hub = 0.018  # rotor hubs above the base origin
    height = 2 * radius  # gain 1 / (1 - 1/64)
    sim, robot = make(sims, QuadrotorConfig(control="motors", aero=("ground_effect",)),
                      start=(0.0, 0.0, height - hub, 0.0), ground=True)
    robot.apply_action(robot.hover_action(sim.gravity))
    run(sim, robot, 1)
    gain = 1 / (1 - (1 / 8) ** 2)
    # hover thrust times the gain, against the weight: one tick's velocity change is g (gain - 1) dt
    assert base(robot)[1][2] == pytest.approx(sim.gravity * (gain - 1) * DT, rel=1e-9)


# ---------------------------------------------------------------------------------------------- pure functions
def test_ground_effect_gain_formula_and_clamp():
    r = 0.02
    z = np.array([0.25, 1.0, 2.0, 100.0]) * r
    gain = ground_effect_gain(z, r)
    np.testing.assert_allclose(gain[1:], 1 / (1 - (r / (4 * z[1:])) ** 2), rtol=1e-15)
    assert gain[0] == pytest.approx(4 / 3)  # held at its value at half a radius, not the pole at R/4
    assert ground_effect_gain(np.array([-1.0]), r)[0] == pytest.approx(4 / 3)
    assert np.all(np.diff(gain) < 0) and gain[-1] == pytest.approx(1.0, abs=1e-5)


def test_rotor_drag_is_linear_in_the_body_velocity_and_the_rotor_speed_sum():
    force = rotor_drag(np.array([1.0, -2.0, 3.0]), np.array([100.0, 200.0, 300.0, 400.0]), 1e-6, 2e-6)
    np.testing.assert_allclose(force, [-1e-3, 2e-3, -6e-3], rtol=1e-15)


def mixer(min_thrust=0.0, max_thrust=0.15) -> tuple[Mixer, np.ndarray]:
    a = 0.0325
    positions = np.array([[a, -a], [-a, -a], [-a, a], [a, a]])
    alloc = allocation(positions, np.array(ROTOR_SPIN), 0.006)
    return Mixer(alloc, min_thrust, max_thrust), alloc


def test_mixer_meets_every_demand_within_range():
    m, alloc = mixer()
    demand = np.array([0.3, 1e-3, -2e-3, 1e-4])
    np.testing.assert_allclose(alloc @ m.mix(demand[0], demand[1:]), demand, rtol=1e-12)


def test_mixer_gives_up_yaw_before_thrust_and_attitude():
    m, alloc = mixer()
    got = alloc @ m.mix(0.3, np.array([1e-3, 0.0, 1.0]))  # far more yaw than the rotors have
    np.testing.assert_allclose(got[:3], [0.3, 1e-3, 0.0], rtol=1e-12, atol=1e-15)
    assert 0 < got[3] < 1.0
    # the yaw kept is the largest that fits: the rotors span the whole range
    f = m.mix(0.3, np.array([1e-3, 0.0, 1.0]))
    assert f.max() - f.min() == pytest.approx(0.15, rel=1e-12)


def test_mixer_moves_thrust_before_attitude_and_scales_roll_pitch_keeping_their_ratio():
    m, alloc = mixer()
    got = alloc @ m.mix(0.58, np.array([2e-3, 1e-3, 0.0]))  # near full thrust plus attitude torque
    np.testing.assert_allclose(got[1:3], [2e-3, 1e-3], rtol=1e-12)
    assert got[0] < 0.58
    f = m.mix(0.3, np.array([1.0, 0.5, 1e-3]))  # more roll and pitch than the rotors can give
    got = alloc @ f
    assert f.min() >= 0.0 and f.max() <= 0.15
    assert got[1] / got[2] == pytest.approx(2.0, rel=1e-12) and got[3] == pytest.approx(0.0, abs=1e-15)
    assert f.max() - f.min() == pytest.approx(0.15)


def test_mixer_with_unequal_shares_moves_the_collective_along_them_and_keeps_the_torques():
    """Six rotors about a centre of mass 10 mm off their centre: the pseudo-inverse loads the near rotors more, and
    a collective beyond the range moves rotor by rotor in those shares, which changes no torque (a common shift of
    every rotor would roll the airframe)."""
    angles = np.radians(30.0 + 60.0 * np.arange(6))
    positions = 0.06 * np.stack([np.cos(angles), np.sin(angles)], axis=1) - [0.01, 0.0]
    alloc = allocation(positions, np.array([1.0, -1.0] * 3), 0.006)
    m = Mixer(alloc, 0.0, 0.15)
    assert sum(m.shares) == pytest.approx(1.0, rel=1e-12) and max(m.shares) / min(m.shares) > 1.5
    demand = np.array([0.85, 2e-4, -1e-4, 5e-5])  # more collective than the rotors give beside these torques
    f = m.mix(demand[0], demand[1:])
    got = alloc @ f
    assert f.min() >= 0.0 and f.max() == pytest.approx(0.15, rel=1e-12) and got[0] < demand[0]
    np.testing.assert_allclose(got[1:], demand[1:], rtol=1e-9)


# ------------------------------------------------------------------------------------------------------ config
@pytest.mark.parametrize(
    "field, value",
    [
        ("control", "attitude"), ("max_roll_rate", 0.0), ("max_pitch_rate", 50.0), ("max_yaw_rate", "2"),
        ("rate_kp_roll_pitch", 0.0), ("rate_kp_yaw", 1e3), ("rate_ki_roll_pitch", -1.0), ("rate_ki_yaw", math.nan),
        ("rate_integral_limit", 0.0), ("aero", ("drag", "drag")), ("aero", ["drag"]), ("aero", ("wind",)),
        ("start_hovering", 1),
    ],
)
def test_config_errors_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        QuadrotorConfig(**{field: value})


@pytest.mark.parametrize(
    "field, value",
    [
        ("thrust_coefficient", 0.0), ("torque_coefficient", 0.0), ("motor_time_constant", 2.0),
        ("min_rotor_speed", -1.0), ("max_rotor_speed", math.inf), ("drag_xy", -1e-7), ("drag_z", 1.0),
        ("rotor_radius", 0.0), ("spin", (1.0, -1.0, 1.0)), ("spin", (1.0, -1.0, 1.0, 0.0)),
    ],
)
def test_airframe_errors_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        replace(quadrotor_model(), **{field: value})


def test_min_rotor_speed_must_stay_below_the_maximum():
    with pytest.raises(ValueError, match="min_rotor_speed"):
        replace(quadrotor_model(), min_rotor_speed=2000.0, max_rotor_speed=1000.0)


# ------------------------------------------------------------------------------------------------- determinism
def trajectory(sim: Sim, robot: Quadrotor, actions: np.ndarray) -> np.ndarray:
    rows = []
    for action in actions:
        robot.apply_action(action)
        run(sim, robot, 4)  # a 60 Hz control step
        s = robot.state()
        rows.append(np.concatenate([s.position, s.rotation.ravel(), s.linear_velocity, robot.rotor_speeds]))
    return np.array(rows)


def test_same_commands_give_the_same_trajectory(sims):
    config = QuadrotorConfig(aero=("drag",), rate_ki_roll_pitch=5.0, rate_ki_yaw=5.0)
    actions = np.random.default_rng(7).uniform(-0.3, 0.3, size=(60, 4))
    first_sim, first = make(sims, config)
    a = trajectory(first_sim, first, actions)
    second_sim, second = make(sims, config)
    b = trajectory(second_sim, second, actions)
    first.reset_to(START)  # a reset clears the rotor speeds and the integrator
    c = trajectory(first_sim, first, actions)
    assert np.abs(a[-1, :3] - START[:3]).max() > 0.01  # it flew
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)


def test_link_states_from_the_base_match_pybullets_link_reads_while_tumbling(sims):
    """The airframe is one merged pybullet body, so its links' states are computed from the base state: they must be
    what pybullet's own link reads of the same URDF loaded link by link give (positions, axes, centre-of-mass
    velocities, rates), to rounding, with its base put in the same state, at full roll and yaw rates."""
    sim, robot = make(sims)
    reference = Sim(physics_hz=HZ)
    sims.append(reference)
    body = reference.load_urdf("links", robot.urdf_path)
    links = reference.link_indices(body)
    tracked = [links[name] for name in robot.link_names]
    robot.apply_action(np.array([0.2, 1.0, -0.7, 1.0]))  # climbing, rolling, pitching and yawing at full rates
    worst = np.zeros(4)
    for _ in range(40):
        run(sim, robot, 6)
        com, quaternion = pb.getBasePositionAndOrientation(robot.body, physicsClientId=sim.client_id)
        linear, angular = pb.getBaseVelocity(robot.body, physicsClientId=sim.client_id)
        pb.resetBasePositionAndOrientation(body, com, quaternion, physicsClientId=reference.client_id)
        pb.resetBaseVelocity(body, linear, angular, physicsClientId=reference.client_id)
        mine, engine = robot.state().links, reference.link_states(body, tracked)
        for k, field in enumerate(("position", "rotation", "linear_velocity", "angular_velocity")):
            worst[k] = max(worst[k], np.abs(getattr(mine, field) - getattr(engine, field)).max())
    assert np.linalg.norm(robot.state().angular_velocity) > 2.0  # it tumbles
    # pybullet's fixed joints are exact (reduced coordinates): the differences are rounding of values near 1
    np.testing.assert_array_less(worst, 1e-12)


# -------------------------------------------------------------------------------------------- the env's hook
def test_env_calls_before_tick_once_per_physics_tick(make_env, monkeypatch):
    from clutter_gym.robots import DiffDriveConfig, DiffDriveRobot
    from clutter_gym.robots.registry import GROUND_ROBOTS

    class Ticked(DiffDriveRobot):
        ticked = True
        ticks = 0

        def before_tick(self) -> None:
            Ticked.ticks += 1

    monkeypatch.setitem(GROUND_ROBOTS, "diff_drive", lambda model, v, w: Ticked(DiffDriveConfig(v, w), model))
    env = make_env("ClutterNav-v1", sensors=())
    env.reset(seed=0)
    env.step(np.zeros(2))
    assert Ticked.ticks == env.unwrapped.substeps > 1


def test_a_urdf_with_mass_off_the_base_is_refused_at_load(tmp_path):
    """pybullet would put the merged body's centre of mass at the mass-weighted link frame origins, not where the
    mass is: load refuses such a URDF instead of flying it with the wrong centre of mass."""
    text = asset_path("robots/quadrotor.urdf").read_text()
    arm = text.index('<link name="arm_1">')  # its mass given at its centre, 27 mm out along its frame's x axis
    moved = text[:arm] + text[arm:].replace('<mass value="0"/>', '<origin xyz="0.027 0 0"/><mass value="0.0005"/>', 1)
    path = tmp_path / "quadrotor.urdf"
    path.write_text(moved.replace('<mass value="0.027"/>', '<mass value="0.0265"/>'))

    class Moved(Quadrotor):
        @property
        def urdf_path(self):
            return path

    sim = Sim(physics_hz=HZ)
    try:
        with pytest.raises(ValueError, match="centre of mass .* put the airframe's mass on base_link"):
            Moved().load(sim)
    finally:
        sim.close()
