"""ClutterFly: a multirotor (a nano quadrotor by default) flies through a cluttered 3D volume to a goal point without
touching anything."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from clutter_gym.builder import EnvSettings, sensor_configs
from clutter_gym.collision import RobotCollisionModel, collision_checker
from clutter_gym.core import ClutterEnv
from clutter_gym.dynamics import flight_dynamics
from clutter_gym.noise.profiles import resolve_noise
from clutter_gym.robots import Multirotor, MultirotorConfig
from clutter_gym.robots.multirotor_model import IMU_LINK, SENSOR_LINK
from clutter_gym.robots.registry import resolve_robot
from clutter_gym.robots.rigid_body import RigidBody
from clutter_gym.sensors import LidarConfig, build_sensors
from clutter_gym.sim import GRAVITY
from clutter_gym.tasks import FlyRewardWeights, FlyTask
from clutter_gym.util.checks import is_number
from clutter_gym.worlds import VolumeArena, VolumeSpec

#: The generator's wall openings, (min, max) width and height in metres, as a share of the volume's height where
#: that is lower than their own: an opening must be lower than the top.
OPENING_SIZE, OPENING_SHARE = (0.8, 1.6), (0.4, 0.8)
#: Hz, the lowest physics rate: the body-rate loop runs once per tick behind the motors' lag, and below it the loop
#: overshoots and no longer brings the airframe back level (docs/envs.md, "Physics rate").
MIN_PHYSICS_HZ = 60.0
#: metres: clearance is resolved this far (or to ``clearance_margin``, if larger); farther reads this. The reward
#: needs only the margin, and resolving the whole volume asked FCL about every shape and obstacle pair each step
#: (docs/quadrotor.md, "Throughput").
CLEARANCE_RANGE = 1.0


#: Every setting of ClutterFly-v1 by its flat name (its gym.make argument) with its default, in the order of its page;
#: clutter_gym.builder.ALIASES gives each its place in the nested form.
SETTINGS = EnvSettings("ClutterFly-v1", MIN_PHYSICS_HZ, {
    "render_mode": None, "sensors": ("imu",), "noise": "none",
    "volume_size": (10.0, 10.0, 4.0), "obstacle_density": 0.05, "ceiling": True,
    "n_rays": 36, "lidar_fov": 2 * math.pi, "lidar_range": LidarConfig.max_range, "lidar_channels": 8,
    "lidar_vertical_fov": math.radians(60.0), "lidar_caster": "exact",
    "camera_size": (64, 64), "camera_modes": ("depth",), "camera_fov": math.radians(58.0), "camera_far": 10.0,
    "camera_renderer": None,
    "physics_hz": 240.0, "control_hz": 30.0, "solver_iterations": 10, "aero": (), "dynamics": "physics",
    "success_radius": 0.3, "clearance_margin": 0.1, "max_tilt": math.pi / 2, "terminate_on_collision": False,
    "contact_tolerance": 1e-3, "collision_fidelity": "primitive", "collision_padding": 0.0, "swept_speed": 0.2,
    "progress_weight": 10.0, "success_weight": 10.0, "crash_weight": 10.0, "contact_weight": 1.0,
    "clearance_weight": 0.5, "control_weight": 0.01, "attitude_weight": 0.1, "rate_weight": 0.01,
    "subgoal_lookahead": 0.0, "observe_thrust_ratio": False, "robot": "quadrotor",
})


class ClutterFlyEnv(ClutterEnv):
    """## Description

    A Crazyflie-sized nano quadrotor (``assets/robots/quadrotor.urdf``, 27 g, flying on per-rotor forces; see
    docs/quadrotor.md), or any multirotor a spec describes (``robot``), starts hovering in a box-shaped volume with a floor, four walls and by default a ceiling,
    cluttered with vertical poles, boxes on the floor or hanging, horizontal beams and walls with one opening, and
    must fly to a goal point. Every generated volume is seeded and guaranteed reachable for a sphere enclosing the
    drone (``worlds/volume/sample.py``). The floor, the walls and the ceiling are obstacles like the clutter. FCL measures
    the exact clearance, pybullet's contact points cross-check it, and swept checks between control steps catch
    contacts that happen between two checks (tunneling); contacts and tunneling are penalised and reported as a
    Safety-Gymnasium style ``info["cost"]``.

    ## Action space

    ``Box(-1, 1, (4,), float32)``: (collective thrust, roll rate, pitch rate, yaw rate), normalised, whatever the
    number of rotors. Thrust ``(a0 + 1) / 2`` of the rotors' maximum (the quadrotor's: 0 to a thrust-to-weight of
    about 2.25; hover near a0 = -0.11);
    body rates ``a1 * 3``, ``a2 * 3``, ``a3 * 2`` rad/s about body x (forward), y (left), z (up), counter-clockwise
    positive. An inner rate loop and mixer turn the command into rotor speeds at the physics rate, and the rotors
    follow with a first-order lag (docs/quadrotor.md). Finite values outside [-1, 1] are clipped; NaN/Inf or a wrong
    shape raise ``ValueError``.

    ## Observation space

    ``Dict``: the entries of each sensor listed in ``sensors`` (docs/sensors.md gives every registered sensor's,
    with their shapes, units and bounds), and these, every one float32:

    | key | shape | content | units, frame | bounds |
    |---|---|---|---|---|
    | ``goal`` | (4,) | goal minus the base origin (x, y, z), then its length | m; body frame | +-volume diagonal, [0, volume diagonal] |
    | ``subgoal`` | (3,) | the point ``subgoal_lookahead`` ahead on the shortest path through the known layout (the progress reward's path), minus the base origin; only with ``subgoal_lookahead > 0`` | m; body frame | +-subgoal_lookahead |
    | ``attitude`` | (3,) | the world's up axis in the body frame (z = cosine of the tilt) | -; body frame | [-1, 1] |
    | ``velocity`` | (6,) | linear velocity (v_x, v_y, v_z), body rates (p, q, r) | m/s, rad/s; body frame | +-20, +-6 |
    | ``rotor_speeds`` | (n rotors,) | rotor speed / max rotor speed, in the robot's ``rotor_links`` order (the quadrotor's: front right, rear right, rear left, front left) | - | [0, 1] |
    | ``thrust_ratio`` | (1,) | the flight controller's estimate of the thrust per unit mass the airframe gets over its nominal model's (motor strength / mass scale; 1 when nominal), filtered over 0.25 s; only with ``observe_thrust_ratio`` | - | [0.25, 4] |

    ``sensors`` is ``("imu",)`` by default. The IMU sits on the ``imu_link`` (body axes, at the centre of mass); the
    LIDAR and the camera on the ``sensor_mount`` link (the quadrotor's: 10 mm above the centre of mass), looking along
    its +x (body +x); rays and the camera see through the drone. The IMU reads +9.81 m/s^2 on z in a level hover.
    With a noise profile the sensor entries carry that profile's noise, update rate (held between updates) and
    latency; ``goal``, ``attitude``, ``velocity``, ``rotor_speeds`` and ``thrust_ratio`` are the flight controller's
    state estimate, taken as exact (``thrust_ratio`` follows from the velocity it differences and the rotor speeds,
    ``robots/thrust_estimate.py``).

    ## Rewards

    Sum of signed terms, each in ``info["reward_terms"]``; weights are constructor arguments:
    ``progress`` (+progress_weight per metre the shortest path to the goal through the clutter shrinks),
    ``success`` (+success_weight once), ``crash`` (-crash_weight once, on leaving the volume, flipping, or a contact
    that ends the episode), ``contact`` (-contact_weight per step with a contact or a tunneling hit),
    ``clearance`` (-clearance_weight * (margin - clearance) / margin per step when clearance < clearance_margin),
    ``control`` (-control_weight * |a - a_hover|^2), ``attitude`` (-attitude_weight * (1 - cos tilt)) and
    ``rate`` (-rate_weight * |body rate|^2, rad/s). ``info["cost"]`` is 1.0 in a step with a contact or a tunneling
    hit, else 0.0.

    ## Starting state

    A new volume per reset from the env's ``np_random`` (or exactly ``options["scene"]``, format in docs/envs.md):
    the drone level, at rest at the start point with yaw ``scene.start[3]``, its rotors at hover speed and the
    hover command held; start and goal at least ``0.4 * max(x, y)`` apart, each with 0.3 m spare clearance beyond
    the drone's bounding radius.

    ## Episode end

    ``terminated`` on success (base within ``success_radius`` of the goal), on leaving the volume (the base
    origin through a wall, above the top or below the floor), on flipping (tilt beyond ``max_tilt``) and, with
    ``terminate_on_collision=True``, on the first step with a contact or a tunneling hit. ``truncated`` by the
    TimeLimit wrapper at ``max_episode_steps`` (600 steps = 20 s at the default 30 Hz).

    ## Info

    ``reward_terms``, ``cost`` and its causes ``cost_<cause>`` (docs/envs.md, "Costs by cause"),
    ``is_success``, ``min_clearance`` (m, FCL, negative = penetration, capped at
    1 m or ``clearance_margin``, whichever is larger), ``closest_pair``, ``witness_points``, ``n_contacts``, ``max_penetration`` (m),
    ``self_collision`` (always None: the airframe is rigid), ``tunneling`` (swept hits), ``pybullet_contacts`` and
    ``contact_disagreement``, ``lidar_ranges`` (m, with ``"lidar"``), ``noise_profile`` (at reset).

    ## Noise

    ``noise`` names a profile (``"none"``, ``"nominal"``, ``"low-cost"``, ``"harsh"``) or overrides one per
    parameter, as for ClutterNav (docs/noise.md): IMU, LIDAR and depth/RGB noise, sensor rates and latencies, action
    latency and noise, and per-episode dynamics randomisation (link masses and inertias, friction, restitution, and
    the rotors' thrust and torque through the motor strength). Rewards and termination always use ground truth.

    ## Arguments

    ``robot`` (a registered multirotor, ``"quadrotor"``, or a ``multirotor`` spec: a mapping or a YAML file;
    docs/robots.md);
    ``render_mode`` (None, "rgb_array", "human"); ``sensors`` (registered sensors' names, docs/sensors.md: those a
    multirotor carries);
    ``noise`` (profile name, override mapping or NoiseProfile); ``volume_size`` (x, y, z) m, x and y in [2, 30],
    z in [1, 5]; ``obstacle_density`` volume fraction [0, 0.25]; ``ceiling``; ``n_rays`` [1, 4096];
    ``lidar_fov`` rad (0, 2 pi]; ``lidar_range`` m; ``lidar_channels`` [1, 128] and ``lidar_vertical_fov`` rad
    [0, pi/2]; ``lidar_caster`` ("exact": beams cast against the true boxes, cylinders and ground, or "pybullet":
    ``rayTestBatch``); ``camera_size`` (width, height) px; ``camera_modes`` (subset of ("rgb", "depth", "segmentation"));
    ``camera_fov`` vertical, rad; ``camera_far`` m; ``camera_renderer`` ("rays": depth and
    segmentation ray cast against the exact shapes; "tiny" or "egl" rasterise, and draw rgb too; None, the default:
    "rays" unless ``camera_modes`` holds "rgb", then "tiny"); ``physics_hz`` (a multiple of ``control_hz``, at least
    :data:`MIN_PHYSICS_HZ`); ``control_hz`` (at least ``physics_hz`` / 1000); ``solver_iterations``; ``aero`` (subset
    of ("drag", "ground_effect")); ``success_radius`` m (0, 2]; ``clearance_margin`` m [0, 1]; ``max_tilt`` rad (0, pi];
    ``terminate_on_collision``; ``contact_tolerance`` m [0, 0.05]; ``collision_fidelity``; ``collision_padding`` m
    [0, 1]; ``swept_speed`` m/s (``inf`` turns swept checks off); ``*_weight`` reward weights [0, 1e4];
    ``subgoal_lookahead`` m [0, volume diagonal] (0: off); ``observe_thrust_ratio`` (the ``thrust_ratio`` entry);
    ``dynamics`` (see "Dynamics").

    ``subgoal_lookahead > 0`` makes the env map-based, as ClutterNav's option of that name: the ``subgoal`` entry
    is a point that far ahead on the shortest path for the drone's bounding sphere through the known layout (the
    path the progress reward measures), so a policy flies a planned path instead of searching the volume.

    Self-collision is not checked: every link of the airframe is fixed to the base, so no pair can move into
    another.

    Settings also nest, by the part they set, as ClutterNav-v1's: ``sensors`` (a mapping from each sensor to its
    settings, ``{"imu": {}, "lidar": {"n_channels": 16}}``), ``world``, ``reward`` and ``collision``; the table of
    defaults gives each argument's place.

    Defaults are in the signature (the module's ``SETTINGS``).

    ## Dynamics

    ``dynamics="physics"`` (the default) flies the airframe in pybullet: the flight controller in Python and a
    ``stepSimulation`` every tick. ``"reduced"`` flies it by its reduced model (:mod:`clutter_gym.dynamics.flight_model`:
    the same rigid body, rotors, rate loop, mixer and aerodynamic effects, integrated per tick in compiled code as
    Bullet integrates a floating base) wherever a step touches nothing: each step is flown by the model first, and
    when the distance it moved any point of the airframe comes within the contact tolerance of the clearance FCL
    measured before it, the step is undone and flown by pybullet from the same state
    (:mod:`clutter_gym.dynamics.reduced_flight`). In free flight the two agree to rounding (micrometres after 20 s of
    tumbling); where contacts begin, pybullet's contact solver keeps its own history, so trajectories that touch
    something part at that step. ``"auto"`` takes the reduced model when it flies a fixed probe within 1 mm of
    pybullet (every airframe a spec describes does; the check guards a model that drifts) and full physics otherwise.
    The reset's ``info["dynamics"]`` says which model runs and why. Mass and motor-strength randomisation and the thrust
    estimate act on the model as on pybullet's body. Its error and its speed: docs/speed-vs-error.md, "Reduced
    dynamics (ClutterFly-v1)".

    ## Version history

    * v1 (clutter-gym 0.3.0): the exact LIDAR caster by default (readings differ from v0's by under a
      millimetre); the swept audit follows rotation (``info["tunneling"]``, and the rewards and costs of the steps
      whose flag changed). ``dynamics`` added, its default (``"physics"``) the earlier behaviour.
    * v0 (clutter-gym 0.1.0-0.2.0): initial release.
    """

    @SETTINGS.sign
    def __init__(self, **settings: Any) -> None:
        s = SETTINGS.resolve(settings)
        if isinstance(s.aero, str) or not isinstance(s.aero, Sequence):
            raise ValueError(f"aero must be a tuple of names from ('drag', 'ground_effect'), got {s.aero!r}")
        make_flyer = resolve_robot(s.robot, "multirotor", SETTINGS.env_id)
        flyer: Multirotor = make_flyer(MultirotorConfig(aero=tuple(s.aero), observe_thrust_ratio=s.observe_thrust_ratio))
        spec = _volume_spec(**s.group("world"))
        # the airframe is rigid (fixed joints only), so self-collision is off and no allowed-collision matrix is
        # needed; the task reads only the robot's clearance, so no link's own is resolved
        checker = collision_checker(flyer, flyer.model.tracked_links,
                                    clearance_range=max(CLEARANCE_RANGE, s.clearance_margin), control_hz=s.control_hz,
                                    self_collision=False, per_link=False, **s.group("collision"))
        radius = bounding_radius(checker.model, flyer.mass_properties)
        configs = sensor_configs(s, sensor_link=SENSOR_LINK, imu_link=IMU_LINK)
        profile = resolve_noise(s.noise)
        sensors = build_sensors(s.sensors, profile, configs, flyer)
        task = FlyTask(FlyRewardWeights(**s.group("reward")), spec=spec, robot_radius=radius,
                       success_radius=s.success_radius, clearance_margin=s.clearance_margin, max_tilt=s.max_tilt,
                       terminate_on_collision=s.terminate_on_collision, hover_action=flyer.hover_action(GRAVITY),
                       subgoal_lookahead=s.subgoal_lookahead)
        super().__init__(
            physics_hz=s.physics_hz,
            solver_iterations=s.solver_iterations,
            robot=flyer,
            arena=VolumeArena(spec, radius, floor_obstacle=True),
            sensors=sensors,
            checker=checker,
            task=task,
            control_hz=s.control_hz,
            noise=profile,
            render_mode=s.render_mode,
            dynamics=flight_dynamics(s.dynamics, flyer, radius + float(np.linalg.norm(flyer.mass_properties.com)),
                                     s.physics_hz, s.solver_iterations, s.control_hz, s.contact_tolerance),
        )


def bounding_radius(model: RobotCollisionModel, body: RigidBody) -> float:
    """Radius of the sphere about the base origin that encloses every collision shape of ``model`` (padding
    included) on the rigid airframe whose link frames ``body`` holds, metres."""
    reach = 0.0
    for shape, radius, padding in zip(model.shapes, model.ball_radius, model.padding):
        origin, rotation = body.frames[shape.link]
        centre = shape.bounding_ball[0]
        point = origin + rotation @ (np.asarray(shape.position) + np.asarray(shape.rotation) @ centre)
        reach = max(reach, float(np.linalg.norm(point)) + float(radius) + float(padding))
    return reach


def _volume_spec(size: Any, obstacle_density: float, ceiling: bool) -> VolumeSpec:
    """The generated volume of the env's arguments; errors name ``volume_size`` where the spec says ``size``. In a
    volume lower than 2 m the wall openings shrink with the height (:data:`OPENING_SHARE`), so every height the spec
    allows can be generated."""
    height = size[2] if isinstance(size, (Sequence, np.ndarray)) and len(size) == 3 else None
    opening = OPENING_SIZE
    if is_number(height) and math.isfinite(height) and height > 0.0:
        (width, tall), (width_share, tall_share) = OPENING_SIZE, OPENING_SHARE
        opening = (min(width, width_share * float(height)), min(tall, tall_share * float(height)))
    try:
        return VolumeSpec(size=size, obstacle_density=obstacle_density, ceiling=ceiling, opening_size=opening)
    except ValueError as exc:
        message = str(exc)
        raise ValueError("volume_" + message if message.startswith("size") else message) from None
