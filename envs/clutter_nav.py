"""ClutterNav: a ground robot crosses a cluttered walled arena to a goal without touching anything."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from clutter_gym.builder import EnvSettings, sensor_configs
from clutter_gym.collision import collision_checker
from clutter_gym.core import ClutterEnv
from clutter_gym.dynamics import ground_dynamics
from clutter_gym.noise.profiles import resolve_noise
from clutter_gym.robots import DiffDriveRobot
from clutter_gym.robots.registry import ground_robot
from clutter_gym.robots.safety import SafetyConfig, SafetyFilter
from clutter_gym.sensors import LidarConfig, build_sensors, sensor_links
from clutter_gym.stages import ForwardOnly, SafetyMonitor
from clutter_gym.tasks import NavigateTask, NavRewardWeights
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.worlds import ClutterArena, ClutterSpec

#: Hz, the lowest physics rate: below it the wheels' contact with the floor does not settle, and a stopped robot creeps
#: and bounces on (docs/envs.md, "Physics rate").
MIN_PHYSICS_HZ = 60.0


#: Every setting of ClutterNav-v1 by its flat name (its gym.make argument) with its default, in the order of its page;
#: clutter_gym.builder.ALIASES gives each its place in the nested form.
SETTINGS = EnvSettings("ClutterNav-v1", MIN_PHYSICS_HZ, {
    "render_mode": None, "sensors": ("lidar", "imu"), "noise": "none",
    "arena_size": 6.0, "obstacle_density": 0.12, "movable_obstacles": 0.0,
    "n_rays": 64, "lidar_fov": 2 * math.pi, "lidar_range": LidarConfig.max_range, "lidar_mount_height": 0.0,
    "lidar_channels": 1, "lidar_vertical_fov": 0.0, "lidar_caster": "exact",
    "camera_size": (84, 84), "camera_modes": ("rgb", "depth"), "camera_fov": math.radians(58.0), "camera_far": 10.0,
    "camera_renderer": "tiny",
    "physics_hz": 120.0, "control_hz": 20.0, "solver_iterations": 10,
    "max_linear_speed": 0.5, "max_angular_speed": 2.0, "success_radius": 0.3, "clearance_margin": 0.1,
    "terminate_on_collision": False, "contact_tolerance": 1e-3, "collision_fidelity": "primitive",
    "collision_padding": 0.0,
    "progress_weight": 10.0, "success_weight": 10.0, "contact_weight": 1.0, "clearance_weight": 0.5,
    "control_weight": 0.01, "time_weight": 0.01, "subgoal_lookahead": 0.0, "reverse_weight": 0.0,
    "safety_horizon": 0.0, "safety_margin": 0.02, "safety_recovery": 0.0, "reverse": True, "observe_bearing": False,
    "robot": "diffbot", "physics": "auto", "dynamics": "physics",
})


class ClutterNavEnv(ClutterEnv):
    """## Description

    A TurtleBot-sized differential-drive robot (``assets/robots/diffbot.urdf``) starts at a random pose in a
    walled square arena strewn with boxes, cylinders and wall segments, and must drive to a goal point. Every
    layout is seeded and guaranteed solvable for the robot's footprint (occupancy-grid path check). Contacts with
    obstacles are penalised and reported as a Safety-Gymnasium style ``info["cost"]``; FCL measures the exact
    clearance and pybullet's contact points cross-check it.

    ## Action space

    ``Box(-1, 1, (2,), float32)``: (linear, angular) velocity command, normalised by ``max_linear_speed`` (m/s)
    and ``max_angular_speed`` (rad/s, counter-clockwise positive). Finite values outside [-1, 1] are clipped;
    NaN/Inf or a wrong shape raise ``ValueError``. Wheel motors track the command under a 1.5 N m torque limit.
    An omnidirectional base (``robot="omnibot"``, or a spec of kind ``omni``) takes ``Box(-1, 1, (3,))``: (forward,
    leftward, angular) in the base frame, the planar speed capped at ``max_linear_speed``
    (:mod:`clutter_gym.robots.omni`).
    With ``reverse=False`` the base drives forwards only: the linear action maps onto [0, max_linear_speed]
    (-1: stand, 0: half speed, 1: full speed), as in mapless-navigation work that gives the policy no way back;
    the base still turns in place. Rewards and the monitor then see that command.

    With ``safety_horizon > 0`` a collision monitor (:mod:`clutter_gym.robots.safety`) sits between the action and
    the motors: it drives the command's arc ``safety_horizon`` seconds ahead against the latest LIDAR scan and
    scales the linear speed down (to 3/4, 1/2, 1/4 or 0) until the footprint keeps ``safety_margin`` from every
    return; the yaw rate passes unchanged. With ``safety_recovery > 0`` it also turns the base in place, away from
    the nearest return, once the whole forward command has been held back for ``safety_recovery`` seconds (a
    navigation stack's "spin" recovery; see the module). Rewards see the policy's action.

    ## Observation space

    ``Dict``: the entries of each sensor listed in ``sensors`` (docs/sensors.md gives every registered sensor's,
    with their shapes, units and bounds), and these, every one float32:

    | key | shape | content | units, frame | bounds |
    |---|---|---|---|---|
    | ``goal`` | (3,) or (4,) | distance, sin(bearing), cos(bearing) (and bearing / pi with ``observe_bearing``) | m, -, -, -; robot frame | [0, arena diagonal], [-1, 1] |
    | ``subgoal`` | (3,) | distance, sin(bearing), cos(bearing) of the waypoint ``subgoal_lookahead`` ahead on the planned path | m, -, -; robot frame | [0, subgoal_lookahead], [-1, 1] |
    | ``velocity`` | (2,), an omnidirectional base's (3,) | forward speed (and leftward speed), yaw rate | m/s, rad/s; base frame | +-2x the commanded maxima |

    ``subgoal`` is present only when ``subgoal_lookahead > 0``. The LIDAR sits on the robot's ``lidar_link``, the
    IMU on its ``imu_link`` and the camera on its ``camera_link`` (the diffbot's: on its front edge); the diffbot's
    LIDAR and camera links face its +x, so the LIDAR's beams are centred on the robot's forward axis and the camera
    looks along it. With a noise profile the sensor entries carry that profile's noise, update rate (held between
    updates) and latency.

    ## Rewards

    Sum of signed terms, each in ``info["reward_terms"]``; weights are constructor arguments:
    ``progress`` (+progress_weight per metre the shortest path to the goal around the clutter shrinks),
    ``success`` (+success_weight once), ``contact`` (-contact_weight per step in contact),
    ``clearance`` (-clearance_weight * (margin - clearance) / margin per step when clearance < clearance_margin),
    ``control`` (-control_weight * |a|^2),
    ``time`` (-time_weight per step), and only when ``reverse_weight > 0`` ``reverse`` (-reverse_weight per m/s
    of backward speed, per step). ``info["cost"]`` is 1.0 in a step with contact, else 0.0.

    ## Starting state

    A new layout per reset from the env's ``np_random`` (or exactly ``options["scene"]``): robot at rest at the
    start pose, goal at least 0.4 * arena_size away, both with 0.15 m spare clearance.

    ## Episode end

    ``terminated`` on success (base within ``success_radius`` of the goal), on flipping (tilt > 60 degrees),
    and on the first contact when ``terminate_on_collision=True``. ``truncated`` by the TimeLimit wrapper at
    ``max_episode_steps`` (400 steps = 20 s at the default 20 Hz).

    ## Info

    ``reward_terms``, ``cost`` and its causes ``cost_<cause>`` (docs/envs.md, "Costs by cause"),
    ``is_success``, ``min_clearance`` (m, FCL, negative = penetration),
    ``n_contacts`` (FCL link/obstacle pairs within ``contact_tolerance``), ``pybullet_contacts`` (pybullet
    contact points within the same tolerance), ``contact_disagreement`` (exactly one engine sees contact),
    ``lidar_ranges`` (m, as the sensor reports them: noisy, and ``inf`` for no return if the profile says so),
    ``noise_profile`` and ``physics`` (at reset: the physics the episode runs at, and why), ``safety_scale`` (the fraction of the linear command the collision monitor let
    through, when it is on) and ``safety_recovery`` (True on the steps of a recovery spin, when the monitor drove
    instead of the policy).

    ## Noise

    ``noise`` names a profile (``"none"``, ``"nominal"``, ``"low-cost"``, ``"harsh"``) or overrides one per
    parameter, e.g. ``{"profile": "nominal", "lidar": {"range_sigma": 0.02}}`` (see :mod:`clutter_gym.noise` and
    docs/noise.md). It sets sensor noise, sensor rates and latencies, action latency and noise, and per-episode
    dynamics randomisation. Noise is drawn from a generator seeded from ``np_random`` at each reset, so a seed
    gives the same layouts under every profile. Rewards and termination always use ground truth.

    ## Arguments

    ``render_mode`` (None, "rgb_array", "human"); ``sensors`` (registered sensors' names, docs/sensors.md);
    ``noise`` (profile name, override mapping or NoiseProfile); ``arena_size`` m [2, 30]; ``obstacle_density``
    floor fraction [0, 0.3]; ``movable_obstacles`` fraction [0, 1] of the generated obstacles that the robot can
    push (see "Movable obstacles"); ``n_rays`` [1, 4096]; ``lidar_fov`` rad (0, 2 pi]; ``lidar_range`` m;
    ``lidar_mount_height`` m above the lidar link; ``lidar_channels`` [1, 128] and ``lidar_vertical_fov`` rad
    [0, pi/2] (a multi-channel 3D LIDAR); ``lidar_caster`` ("exact": beams cast against the true boxes, cylinders
    and ground, or "pybullet": ``rayTestBatch``); ``camera_size`` (width, height) px; ``camera_modes`` (subset of
    ("rgb", "depth", "segmentation")); ``camera_fov`` vertical, rad; ``camera_far`` m; ``camera_renderer``
    ("tiny", "egl", or "rays": depth and segmentation only, ray cast against the exact shapes); ``physics_hz`` (a
    multiple of ``control_hz``, at least :data:`MIN_PHYSICS_HZ`); ``control_hz`` (at least ``physics_hz`` / 1000);
    ``solver_iterations``; ``max_linear_speed`` m/s; ``max_angular_speed`` rad/s; ``success_radius`` m;
    ``clearance_margin`` m; ``terminate_on_collision``; ``contact_tolerance`` m; ``collision_fidelity`` (one of
    ``FIDELITY_LEVELS``: docs/collision.md); ``collision_padding`` m;
    ``*_weight`` reward weights; ``subgoal_lookahead`` m (0: off); ``safety_horizon`` s [0, 2] (0: off),
    ``safety_margin`` m [0, 0.5] and ``safety_recovery`` s [0, 10] (0: never) (need a 2D ``lidar`` in
    ``sensors``); ``reverse`` (False: forward driving only, see "Action space"); ``robot`` (a registered wheeled
    or omnidirectional base, a spec mapping or a YAML spec file: docs/robots.md; the monitor needs a wheeled one); ``observe_bearing``
    (the goal entry ends with the bearing angle / pi, which jumps where the goal is straight behind: from sin and cos
    alone, a continuous policy's turn passes through zero there, and a deterministic one can stop for good);
    ``physics`` ("auto": a user scene that stacks movable obstacles ticks faster with more solver iterations, as
    much as it needs and never less than ``physics_hz`` and ``solver_iterations``, and the reset's
    ``info["physics"]`` says what it chose and why; "fixed": always ``physics_hz`` and ``solver_iterations``);
    ``dynamics`` (see "Dynamics").

    ``subgoal_lookahead > 0`` makes the env map-based: the ``subgoal`` entry comes from a path planned on the
    known layout (shortest on a costmap that charges passing within 0.25 m of touching; see
    ``worlds/floor/path.py``), as a global planner on a map hands waypoints to a local controller. The default
    env is mapless: it knows only the goal's relative position.

    Settings also nest, by the part they set: ``sensors`` takes a mapping from each sensor the env carries to its
    settings (``{"lidar": {"n_rays": 128}, "imu": {}}``: the LIDAR and the IMU, in that order), and ``world``,
    ``reward``, ``safety`` and ``collision`` each take a mapping of theirs (``reward={"progress": 5.0}``). A nested
    name is the field of the part's own settings object; the table of defaults gives each argument's place. A
    setting given both flat and nested is refused; a bad value is named by its flat argument.

    Defaults are in the signature (the module's ``SETTINGS``).

    ## Dynamics

    ``dynamics="physics"`` (the default) simulates the base in pybullet, wheel-floor contact included, every tick.
    ``"reduced"`` moves a differential drive by its reduced model (:mod:`clutter_gym.dynamics.drive_model`: a
    unicycle whose sides follow their commands through a first-order lag under an acceleration limit, fitted to the
    full-physics robot when the env is made) and does not step pybullet while FCL's clearance exceeds the distance
    the base can cover in one step; nearer than that, the step runs under full physics from the model's state
    (:mod:`clutter_gym.dynamics.reduced_drive`), and an episode with a movable obstacle runs under full physics
    throughout. ``"auto"`` takes the reduced model when its fit is within 10% of the robot's speeds (the diffbot's is,
    the skid-steer Husky's is not) and full physics otherwise. The reset's ``info["dynamics"]`` says which model the
    episode starts under and why. Motor strength, mass and friction randomisation scale the model's acceleration
    limit; action latency and noise act on its command as on the motors'. Its error against full physics and its
    speed: docs/benchmarks.md, "Reduced dynamics".

    ## Movable obstacles

    ``movable_obstacles`` makes that fraction of each generated layout movable, at the density of empty cardboard
    boxes (``ClutterSpec.movable_density``); a user scene gives any obstacle a ``mass``. The layout is the same
    whatever the fraction. Touching a movable obstacle is a contact like any other (it costs and, with
    ``terminate_on_collision``, ends the episode); the collision checker and the camera follow where the physics
    moves it. The path distance behind the progress reward is computed on the layout as placed at reset.

    ## Version history

    * v1 (clutter-gym 0.3.0): ``physics="auto"`` by default (stacked movable obstacles tick at the rate that
      holds them); the exact LIDAR caster by default (readings differ from v0's by under a millimetre); the swept
      audit follows rotation (``info["tunneling"]``, and with it rewards and costs, change on the steps whose flag
      changed).
    * v0 (clutter-gym 0.1.0-0.2.0): initial release; camera sensor, noise profiles, sensor timing, action noise and
      dynamics randomisation
      added without changing the clean defaults. The progress term follows the path distance around the
      clutter instead of the straight-line distance (PPO stalled behind obstacles with the latter). The collision
      monitor (``safety_horizon``) and its recovery spin (``safety_recovery``) added, off by default. Movable
      obstacles (``movable_obstacles``, a scene's ``mass``) added, off by default. Forward-only driving
      (``reverse=False``) and the bearing angle in the goal entry (``observe_bearing``) added, off by default.
    """

    @SETTINGS.sign
    def __init__(self, **settings: Any) -> None:
        s = SETTINGS.resolve(settings)
        self.forward_only = not s.reverse  # the linear action maps onto stand..full speed (stages.ForwardOnly)
        drive = ground_robot(s.robot, SETTINGS.env_id, s.max_linear_speed, s.max_angular_speed)
        base = drive.base
        spec = ClutterSpec(**s.group("world"))
        configs = sensor_configs(s)
        profile = resolve_noise(s.noise)
        sensors = build_sensors(s.sensors, profile, configs, drive)
        _check_sensor_links(s.sensors, base)
        task = NavigateTask(NavRewardWeights(**s.group("reward")), success_radius=s.success_radius,
                            clearance_margin=s.clearance_margin, terminate_on_collision=s.terminate_on_collision,
                            max_goal_distance=math.sqrt(2.0) * s.arena_size, spec=spec,
                            robot_radius=base.footprint_radius, subgoal_lookahead=s.subgoal_lookahead,
                            observe_bearing=s.observe_bearing)
        # the whole arena is in range: every step reports the distance to the nearest obstacle
        checker = collision_checker(drive, base.tracked_links, clearance_range=math.sqrt(2.0) * s.arena_size,
                                    control_hz=s.control_hz, **s.group("collision"))
        safety = _safety_filter(SafetyConfig(**s.group("safety")), s.sensors, configs["lidar"], drive, s.control_hz)
        super().__init__(
            physics_hz=s.physics_hz,
            solver_iterations=s.solver_iterations,
            robot=drive,
            arena=ClutterArena(spec, base.footprint_radius),
            sensors=sensors,
            checker=checker,
            task=task,
            control_hz=s.control_hz,
            noise=profile,
            render_mode=s.render_mode,
            stages=[*([ForwardOnly()] if self.forward_only else []), *([SafetyMonitor(safety)] if safety else [])],
            physics=s.physics,
            dynamics=ground_dynamics(s.dynamics, drive, s.physics_hz, s.solver_iterations, s.control_hz,
                                     s.contact_tolerance),
        )


def _check_sensor_links(sensors: Sequence[str], base: Any) -> None:
    """Refuse sensors whose link the robot's URDF lacks, naming them and the links it has."""
    links = UrdfKinematics(base.urdf).links
    missing = [link for link in sensor_links(sensors) if link not in links]
    if missing:
        raise ValueError(f"robot {base.name!r} has no {missing} for sensors {list(sensors)}; mount them in its spec "
                         f"(mounts) or drop those sensors (its links: {links})")


def _safety_filter(config: SafetyConfig, sensors: Sequence[str], lidar: LidarConfig,
                   robot: Any, control_hz: float) -> SafetyFilter | None:
    """The collision monitor over the LIDAR's returns, in the base frame (None when its horizon is 0)."""
    if config.horizon == 0.0:
        return None
    if not isinstance(robot, DiffDriveRobot):
        raise ValueError(f"safety_horizon > 0 needs a differential drive (the monitor drives its arcs); robot "
                         f"{robot.name!r} is not one")
    if "lidar" not in sensors or lidar.n_channels != 1:
        raise ValueError(f"safety_horizon > 0 needs a 2D LIDAR: 'lidar' in sensors and lidar_channels 1, got "
                         f"sensors {list(sensors)} and lidar_channels {lidar.n_channels}")
    kinematics = UrdfKinematics(robot.urdf_path)
    mount = kinematics.forward(np.zeros((1, len(kinematics.joints))))[lidar.link][0]
    yaw = math.atan2(mount[1, 0], mount[0, 0])
    c = robot.config
    return SafetyFilter(config, c.footprint_radius, c.max_linear_speed, c.max_angular_speed,
                        lidar.angles + yaw, (float(mount[0, 3]), float(mount[1, 3])), lidar.max_range, 1.0 / control_hz)

