"""ClutterReach: a Franka Panda brings its end effector to a target among clutter on a table and in a shelf."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from clutter_gym.collision import collision_checker
from clutter_gym.core import ClutterEnv
from clutter_gym.make_checks import check_env_settings, check_flags, check_numbers, check_physics_mode
from clutter_gym.noise.profiles import NoiseProfile, resolve_noise
from clutter_gym.planning.joint_space import ArmPlanner
from clutter_gym.robots.arm import Arm, ArmConfig
from clutter_gym.robots.registry import resolve_robot
from clutter_gym.sensors import build_sensors, camera_config
from clutter_gym.tasks import ReachRewardWeights, ReachTask
from clutter_gym.worlds import TableSpec, TabletopArena

#: Hz, the lowest physics rate: the Panda's joint motors hold their targets through pybullet's constraint solver
#: once per tick, and below it the arm sags under gravity and is still moving long after a stop (docs/envs.md,
#: "Physics rate").
MIN_PHYSICS_HZ = 60.0
#: Clearance the subgoal's planner keeps from the layout, metres (on top of ``collision_padding``).
SUBGOAL_MARGIN = 0.02
#: The wrist camera's frame in the end effector's (roll, pitch, yaw): it looks along the hand's z axis (its approach
#: axis), its image's up along the hand's x axis.
WRIST_CAMERA_RPY = (math.pi, -math.pi / 2, 0.0)


class ClutterReachEnv(ClutterEnv):
    """## Description

    A Franka Emika Panda (pybullet_data ``franka_panda/panda.urdf``, fixed base, fingers half open) stands at
    the back of a table crowded with boxes, cylinders and a shelf, and must bring its end effector (between the
    fingertips) to a target point without touching the clutter or itself. FCL measures every link's clearance
    at the chosen ``collision_fidelity``, checks the self-collision pairs the allowed-collision matrix enables,
    and sweeps fast links between control steps to catch contacts that happen between two checks (tunneling).
    Contacts, self-contacts and tunneling are penalised and reported as a Safety-Gymnasium style
    ``info["cost"]``.

    ## Action space

    ``control="joint_velocity"`` (default): ``Box(-1, 1, (7,), float32)``, joint-velocity commands as a
    fraction ``max_joint_speed`` of the URDF velocity limits (2.175 rad/s for joints 1-4, 2.61 for 5-7); each
    step moves the joint targets by command x control period, clamped to the joint limits.
    ``control="ee_position"``: ``Box(-1, 1, (3,), float32)``, an end-effector displacement of up to
    ``max_ee_step`` metres per step along world x, y, z, through pybullet's IK with the hand pointing down.
    Finite values outside [-1, 1] are clipped; NaN/Inf or a wrong shape raise ``ValueError``.

    ## Observation space

    ``Dict``, every entry float32:

    | key | shape | content | units, frame | bounds |
    |---|---|---|---|---|
    | ``joint_position`` | (7,) | arm joint positions | rad | the URDF limits |
    | ``joint_velocity`` | (7,) | arm joint velocities | rad/s | +-2x the URDF limits |
    | ``ee_position`` | (3,) | end-effector position | m, world (base at origin) | +-1.5 |
    | ``target`` | (3,) | target position | m, world | +-1.5 |
    | ``clearance`` | (10,) | signed FCL distance of each moving link (panda_link1..7, hand, fingers) to the nearest obstacle | m | +-clearance_range |
    | ``clearance_direction`` | (10, 3) | unit vector from each link's witness point to its obstacle's (only with ``observe_directions=True``; zero beyond range or in contact) | world | [-1, 1] |
    | ``target_offset`` | (3,) | target minus end effector (only with ``observe_target_offset=True``) | m, world | +-3 |
    | ``camera_depth`` | (h, w) | the wrist camera's depth along its optical axis, 0 = no data (only with ``sensors=("camera",)``; ``camera_modes`` may add ``camera_segmentation``) | m; the camera on the end effector, looking along the hand's approach axis | [0, camera_far] |
    | ``subgoal`` | (7,) | the point ``subgoal_lookahead`` ahead on the joint-space path planned on the known layout, minus the joint positions (zero if no path was found; only with ``subgoal_lookahead > 0``) | rad | +-6 |

    ## Rewards

    Sum of signed terms, each in ``info["reward_terms"]``; weights are constructor arguments:
    ``progress`` (+progress_weight per metre the end effector closes on the target), ``success``
    (+success_weight once), ``contact`` (-contact_weight per step touching an obstacle or the table),
    ``self_contact`` (-self_contact_weight per step in self-collision), ``clearance`` (-clearance_weight *
    (margin - clearance) / margin when the arm's clearance < clearance_margin), ``tunneling``
    (-tunneling_weight per swept hit the end-of-step check missed), ``control`` (-control_weight * |a|^2).
    ``info["cost"]`` is 1.0 in a step with contact, self-contact or tunneling, else 0.0.

    ## Starting state

    A new layout per reset from the env's ``np_random`` (or exactly ``options["scene"]``, format in
    docs/envs.md): up to ``n_obstacles`` boxes and cylinders and, with ``shelf=True``, a shelf on the table; the arm at
    rest in the ready pose plus uniform noise of +-0.1 rad per joint, clear of everything; the target at least
    0.06 m from every obstacle within the arm's reach, inside the shelf in 30% of layouts.

    ## Episode end

    ``terminated`` on success (end effector within ``success_radius`` of the target) and, with
    ``terminate_on_collision=True``, on the first contact, self-contact or tunneling. ``truncated`` by the
    TimeLimit wrapper at ``max_episode_steps`` (100 steps = 5 s at the default 20 Hz).

    ## Info

    ``reward_terms``, ``cost`` and its causes ``cost_<cause>`` (docs/envs.md, "Costs by cause"),
    ``is_success``, ``min_clearance`` (m, FCL, negative = penetration, capped at
    ``clearance_range``), ``closest_pair`` ((link, obstacle index) or None), ``witness_points`` ((2, 3) world
    points on the link and the obstacle, or None), ``n_contacts``, ``max_penetration`` (m), ``self_collision``
    ((link, link) or None), ``tunneling`` (swept hits), ``pybullet_contacts`` and ``contact_disagreement``
    (pybullet's contact points against FCL's verdict), ``noise_profile`` and ``physics`` (at reset: the physics the episode runs at, and why).

    ## Arguments

    ``robot`` (a registered arm, a spec mapping or a YAML spec file: docs/robots.md); ``physics`` ("auto" or
    "fixed", as ClutterNav-v1's);
    ``render_mode``; ``control`` ("joint_velocity", "ee_position"); ``max_joint_speed`` (0, 1];
    ``max_ee_step`` m; ``collision_fidelity`` (one of ``FIDELITY_LEVELS``: docs/collision.md);
    ``collision_padding`` m; ``self_collision``; ``n_obstacles`` [0, 20]; ``movable_obstacles`` fraction [0, 1]
    of them that the arm can push (at the density of packed groceries, ``TableSpec.movable_density``; a user
    scene gives any obstacle a ``mass``; the shelf stays put; movable clutter starts 5 mm above the table, as
    static clutter stands, and settles onto it in its first ticks; the planner behind ``subgoal`` plans on the layout
    as placed); ``shelf``; ``noise`` (profile name
    or overrides; action noise, timing and dynamics, and the camera's depth noise); ``sensors`` (() or
    ("camera",): a wrist depth camera at the end effector, looking along the hand's approach axis, its image's up
    along the hand's x axis, ray cast against the world's exact shapes (robots are not drawn, so the fingers do not
    fill its view)); ``camera_size`` (width, height) px; ``camera_modes`` (subset of ("depth", "segmentation"));
    ``camera_fov`` vertical, rad; ``camera_far`` m;
    ``physics_hz`` (a multiple of ``control_hz``, at least :data:`MIN_PHYSICS_HZ`); ``control_hz`` (at least
    ``physics_hz`` / 1000); ``solver_iterations``; ``success_radius`` m; ``clearance_margin`` m; ``clearance_range`` m;
    ``observe_directions``; ``observe_target_offset``; ``terminate_on_collision``;
    ``contact_tolerance`` m; ``swept_speed`` m/s (``inf`` turns swept checks off); ``*_weight`` reward weights;
    ``subgoal_lookahead`` rad [0, 3] (0: off).

    ``subgoal_lookahead > 0`` makes the env map-based: at every reset a joint-space planner
    (``clutter_gym.planning.joint_space``: IK goals, RRT-Connect, shortcutting, 2 cm clearance plus
    ``collision_padding`` at ``collision_fidelity``) plans on the known layout, as a global planner hands a local
    controller its path; the ``subgoal`` entry is the point that far ahead along it. Its random stream is drawn
    from the layout, so a seed still fixes the episode.

    ## Version history

    * v1 (clutter-gym 0.3.0): ``physics="auto"`` by default; the swept audit follows rotation
      (``info["tunneling"]``, and the rewards and costs of the steps whose flag changed).
    * v0 (clutter-gym 0.1.0-0.2.0): initial release; movable obstacles (``movable_obstacles``, a scene's ``mass``)
      added, off by default.
    """

    def __init__(
        self,
        render_mode: str | None = None,
        control: str = "joint_velocity",
        max_joint_speed: float = 0.5,
        max_ee_step: float = 0.05,
        collision_fidelity: str = "convex",
        collision_padding: float = 0.0,
        self_collision: bool = True,
        n_obstacles: int = 6,
        movable_obstacles: float = 0.0,
        shelf: bool = True,
        noise: str | Mapping[str, Any] | NoiseProfile | None = "none",
        physics_hz: float = 240.0,
        control_hz: float = 20.0,
        solver_iterations: int = 10,
        success_radius: float = 0.05,
        clearance_margin: float = 0.05,
        clearance_range: float = 0.3,
        observe_directions: bool = False,
        observe_target_offset: bool = False,
        terminate_on_collision: bool = False,
        contact_tolerance: float = 1e-3,
        swept_speed: float = 0.2,
        progress_weight: float = 10.0,
        success_weight: float = 10.0,
        contact_weight: float = 1.0,
        self_contact_weight: float = 1.0,
        clearance_weight: float = 0.2,
        tunneling_weight: float = 1.0,
        control_weight: float = 0.005,
        subgoal_lookahead: float = 0.0,
        robot: str = "panda",
        physics: str = "auto",
        sensors: Sequence[str] = (),
        camera_size: tuple[int, int] = (32, 32),
        camera_modes: Sequence[str] = ("depth",),
        camera_fov: float = math.radians(58.0),
        camera_far: float = 2.0,
    ) -> None:
        check_numbers(ClutterReachEnv.__init__, locals())
        check_env_settings(render_mode, physics_hz, control_hz, solver_iterations, contact_tolerance,
                           env_id="ClutterReach-v1", min_physics_hz=MIN_PHYSICS_HZ)
        check_physics_mode(physics)
        check_flags(self_collision=self_collision, shelf=shelf, observe_directions=observe_directions,
                    observe_target_offset=observe_target_offset, terminate_on_collision=terminate_on_collision)
        if not (math.isfinite(clearance_range) and 0.01 <= clearance_range <= 2.0):
            raise ValueError(f"clearance_range must be in [0.01, 2] metres, got {clearance_range!r}")
        if not (swept_speed > 0.0):  # inf allowed: no swept checks
            raise ValueError(f"swept_speed must be > 0 m/s (inf disables swept checks), got {swept_speed!r}")
        if tuple(sensors) not in ((), ("camera",)):
            raise ValueError(f"sensors must be () or ('camera',) (a wrist camera), got {sensors!r}")
        make_arm = resolve_robot(robot, "arm", "ClutterReach-v1")
        arm: Arm = make_arm(ArmConfig(control, max_joint_speed, max_ee_step), control_dt=1.0 / control_hz)
        model = arm.model
        profile = resolve_noise(noise)
        camera = camera_config(camera_size, camera_modes, camera_fov, camera_far, "rays", model.ee_link,
                               mount_rpy=WRIST_CAMERA_RPY)
        checker = collision_checker(arm, model.tracked_links, collision_fidelity, collision_padding,
                                    contact_tolerance, clearance_range, control_hz, self_collision=self_collision,
                                    swept_speed=swept_speed, fixed_links=(arm.base_link, *model.fixed_links))
        task = ReachTask(
            ReachRewardWeights(progress=progress_weight, success=success_weight, contact=contact_weight,
                               self_contact=self_contact_weight, clearance=clearance_weight,
                               tunneling=tunneling_weight, control=control_weight),
            ee_row=model.ee_row,
            links=checker.links,
            success_radius=success_radius,
            clearance_margin=clearance_margin,
            clearance_range=clearance_range,
            terminate_on_collision=terminate_on_collision,
            observe_directions=observe_directions,
            observe_offset=observe_target_offset,
            subgoal_lookahead=subgoal_lookahead,
            make_planner=lambda: ArmPlanner(SUBGOAL_MARGIN + collision_padding, collision_fidelity, model),
        )
        super().__init__(
            physics_hz=physics_hz,
            solver_iterations=solver_iterations,
            robot=arm,
            arena=TabletopArena(TableSpec(n_obstacles=n_obstacles, shelf=bool(shelf), movable_fraction=movable_obstacles),
                                model.ready, model.lower, model.upper, model.shoulder, model.reach),
            sensors=build_sensors(sensors, profile, {"camera": camera}, arm),
            checker=checker,
            task=task,
            control_hz=control_hz,
            noise=profile,
            render_mode=render_mode,
            physics=physics,
        )
