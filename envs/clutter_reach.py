"""ClutterReach: a Franka Panda brings its end effector to a target among clutter on a table and in a shelf."""

from __future__ import annotations

import math
from typing import Any

from clutter_gym.builder import EnvSettings
from clutter_gym.collision import collision_checker
from clutter_gym.core import ClutterEnv
from clutter_gym.dynamics import arm_dynamics
from clutter_gym.noise.profiles import resolve_noise
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


#: Every setting of ClutterReach-v1 by its flat name (its gym.make argument) with its default, in the order of its
#: page; clutter_gym.builder.ALIASES gives each its place in the nested form.
SETTINGS = EnvSettings("ClutterReach-v1", MIN_PHYSICS_HZ, {
    "render_mode": None, "control": "joint_velocity", "max_joint_speed": 0.5, "max_ee_step": 0.05,
    "collision_fidelity": "convex", "collision_padding": 0.0, "self_collision": True,
    "n_obstacles": 6, "movable_obstacles": 0.0, "shelf": True, "noise": "none",
    "physics_hz": 240.0, "control_hz": 20.0, "solver_iterations": 10,
    "success_radius": 0.05, "clearance_margin": 0.05, "clearance_range": 0.3,
    "observe_directions": False, "observe_target_offset": False, "terminate_on_collision": False,
    "contact_tolerance": 1e-3, "swept_speed": 0.2,
    "progress_weight": 10.0, "success_weight": 10.0, "contact_weight": 1.0, "self_contact_weight": 1.0,
    "clearance_weight": 0.2, "tunneling_weight": 1.0, "control_weight": 0.005, "subgoal_lookahead": 0.0,
    "robot": "panda", "physics": "auto", "dynamics": "physics", "sensors": (),
    "camera_size": (32, 32), "camera_modes": ("depth",), "camera_fov": math.radians(58.0), "camera_far": 2.0,
})


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
    "fixed", as ClutterNav-v1's); ``dynamics`` (see "Dynamics");
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

    Settings also nest, by the part they set, as ClutterNav-v1's: ``sensors`` (``{"camera": {"size": (64, 64)}}``),
    ``world`` (``{"n_obstacles": 3, "shelf": False}``), ``reward`` and ``collision``; the table of defaults gives each
    argument's place.

    ``subgoal_lookahead > 0`` makes the env map-based: at every reset a joint-space planner
    (``clutter_gym.planning.joint_space``: IK goals, RRT-Connect, shortcutting, 2 cm clearance plus
    ``collision_padding`` at ``collision_fidelity``) plans on the known layout, as a global planner hands a local
    controller its path; the ``subgoal`` entry is the point that far ahead along it. Its random stream is drawn
    from the layout, so a seed still fixes the episode.

    ## Dynamics

    ``dynamics="physics"`` (the default) moves the arm by pybullet's joint motors and its constraint solver every
    tick. ``"reduced"`` moves its joints by the motors' own law (:mod:`clutter_gym.dynamics.arm_model`: each joint gets
    the velocity its position motor asks for, as if its force were unlimited) wherever a step touches nothing: the
    model's step is taken when the farthest any point of the arm can have moved (each joint's turn times the reach of
    the links beyond it) stays within the clearance FCL measured before it, less the contact tolerance, and pybullet's
    joints are then set to the model's, so its forward kinematics place the links; otherwise the step runs under full
    physics (:mod:`clutter_gym.dynamics.reduced_arm`). An episode with a movable obstacle runs under full physics
    throughout. ``"auto"`` takes the reduced model when it keeps the hand within 2 cm of pybullet's over a fixed probe
    (the Panda's is within about 1 cm: the model leaves out the force limits and the coupling of the joints that
    pybullet's solver meets) and full physics otherwise. The reset's ``info["dynamics"]`` says which model runs and
    why. Its error and its speed: docs/speed-vs-error.md, "Reduced dynamics (ClutterReach-v1)".

    ## Version history

    * v1 (clutter-gym 0.3.0): ``physics="auto"`` by default; ``dynamics`` added, its default (``"physics"``) the
      earlier behaviour; the swept audit follows rotation
      (``info["tunneling"]``, and the rewards and costs of the steps whose flag changed).
    * v0 (clutter-gym 0.1.0-0.2.0): initial release; movable obstacles (``movable_obstacles``, a scene's ``mass``)
      added, off by default.
    """

    @SETTINGS.sign
    def __init__(self, **settings: Any) -> None:
        s = SETTINGS.resolve(settings)
        if not (math.isfinite(s.clearance_range) and 0.01 <= s.clearance_range <= 2.0):
            raise ValueError(f"clearance_range must be in [0.01, 2] metres, got {s.clearance_range!r}")
        if tuple(s.sensors) not in ((), ("camera",)):
            raise ValueError(f"sensors must be () or ('camera',) (a wrist camera), got {s.sensors!r}")
        make_arm = resolve_robot(s.robot, "arm", SETTINGS.env_id)
        arm: Arm = make_arm(ArmConfig(s.control, s.max_joint_speed, s.max_ee_step), control_dt=1.0 / s.control_hz)
        model = arm.model
        profile = resolve_noise(s.noise)
        camera = camera_config(**s.group("sensors", "camera"), renderer="rays", link=model.ee_link,
                               mount_rpy=WRIST_CAMERA_RPY)
        checker = collision_checker(arm, model.tracked_links, clearance_range=s.clearance_range,
                                    control_hz=s.control_hz, fixed_links=(arm.base_link, *model.fixed_links),
                                    **s.group("collision"))
        radii = checker.model.link_radii()
        task = ReachTask(ReachRewardWeights(**s.group("reward")), ee_row=model.ee_row, links=checker.links,
                         success_radius=s.success_radius, clearance_margin=s.clearance_margin,
                         clearance_range=s.clearance_range, terminate_on_collision=s.terminate_on_collision,
                         observe_directions=s.observe_directions, observe_offset=s.observe_target_offset,
                         subgoal_lookahead=s.subgoal_lookahead,
                         make_planner=lambda: ArmPlanner(SUBGOAL_MARGIN + s.collision_padding, s.collision_fidelity,
                                                         model))
        super().__init__(
            physics_hz=s.physics_hz,
            solver_iterations=s.solver_iterations,
            robot=arm,
            arena=TabletopArena(TableSpec(**s.group("world")), model.ready, model.lower, model.upper, model.shoulder,
                                model.reach),
            sensors=build_sensors(s.sensors, profile, {"camera": camera}, arm),
            checker=checker,
            task=task,
            control_hz=s.control_hz,
            noise=profile,
            render_mode=s.render_mode,
            physics=s.physics,
            dynamics=arm_dynamics(s.dynamics, arm, {link: radii[link] for link in checker.links}, s.physics_hz,
                                  s.solver_iterations, s.control_hz, s.contact_tolerance),
        )
