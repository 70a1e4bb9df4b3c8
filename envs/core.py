"""ClutterEnv: a Gymnasium env composed of a Sim, a robot, an arena, sensors, a collision checker and a task.

It only wires the parts together (docs/architecture.md, "One step"); every decision about physics, layout,
sensing, collision or reward lives in the part that owns it, behind the contracts of :mod:`clutter_gym.interfaces`.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from clutter_gym.auto_physics import PhysicsChoice, choose_physics
from clutter_gym.collision import CollisionChecker, RobotCollisionModel, check_fidelity
from clutter_gym.datatypes import CollisionReport, RobotState
from clutter_gym.interfaces import Arena, L, Layout, Robot, Sensor, Task, TickedRobot
from clutter_gym.make_checks import RENDER_MODES, check_keywords
from clutter_gym.noise.action import ActionChannel
from clutter_gym.noise.dynamics import sample_dynamics
from clutter_gym.noise.profiles import NoiseProfile
from clutter_gym.robots.safety import SafetyFilter
from clutter_gym.sensors.timing import SampleHoldDelay, timed_reading
from clutter_gym.sim import Sim
from clutter_gym.util.camera_view import CameraView, orbit_angles
from clutter_gym.util.checks import is_number
from clutter_gym.util.overlay import draw_marks
from clutter_gym.util.transforms import yaw_quat

TRAIL_LENGTH = 400  # control steps of the robot's path that rgb_array frames draw


class ClutterEnv(gym.Env):
    """Composition of the parts; see :class:`clutter_gym.clutter_nav.ClutterNavEnv` for a documented env.

    Args:
        physics_hz: physics ticks per simulated second; the env opens its own physics client (:class:`Sim`, a GUI
            one for ``render_mode="human"``) and closes it in :meth:`close`.
        solver_iterations: constraint solver iterations per physics tick.
        robot: loaded into the client here.
        arena: loaded into the client here; chooses and places each episode's scene.
        sensors: read after every step, in order (each fills the observation keys in its ``spaces``).
        checker: FCL model of the robot against the scene.
        task: reward, termination and the goal observation.
        control_hz: actions per simulated second; ``physics_hz`` must be a multiple of it.
        noise: sensor timing, actuation noise and dynamics randomisation (the sensors carry their own noise).
        render_mode: None, "rgb_array" or "human".
        render_size: (width, height) of rgb_array frames in pixels.
        safety: slows each action's linear command by what the latest reading of its sensor (``safety.sensor``, one
            of ``sensors``) allows, and spins the base free when it stays pinned, before actuation noise and latency
            (None: actions pass unchanged).
        physics: "fixed" runs every episode at ``physics_hz`` and ``solver_iterations``; "auto" raises them for a
            scene that needs more (:func:`clutter_gym.auto_physics.choose_physics`), never lowers them, and says what
            it chose in the reset's ``info["physics"]``.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 20}
    arena: Arena[Any]  # and the task: of one layout type, which __init__'s signature holds them to
    task: Task[Any]

    def __new__(cls, *args: Any, **kwargs: Any) -> ClutterEnv:
        """Check the keyword arguments against the env's own before it is built: a misspelt one is named with the
        closest allowed name and the whole list, where Python would only say "unexpected keyword argument"."""
        check_keywords(cls, kwargs)
        return super().__new__(cls)

    def __init__(
        self,
        physics_hz: float,
        solver_iterations: int,
        robot: Robot,
        arena: Arena[L],
        sensors: Sequence[Sensor],
        checker: CollisionChecker,
        task: Task[L],
        control_hz: float,
        noise: NoiseProfile,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (320, 240),
        safety: SafetyFilter | None = None,
        physics: str = "fixed",
    ) -> None:
        self.sensors = tuple(sensors)
        # an env that never draws gives its obstacles no visual shapes (docs/design-notes.md#obstacle-visuals)
        visuals = render_mode is not None or any(s.renders for s in self.sensors)
        sim = Sim(physics_hz=physics_hz, solver_iterations=solver_iterations, gui=render_mode == "human",
                  visuals=visuals)
        self.sim, self.robot, self.arena, self.checker, self.task = sim, robot, arena, checker, task
        # a large scene keeps its far obstacles out of the physics unless something reads every body
        arena.near_field = not visuals and not any(s.needs_bodies for s in self.sensors)
        self.safety = safety
        self._scan: np.ndarray | None = None  # the reading of the safety filter's sensor delivered last
        self._scan_from = _sensor_named(self.sensors, safety.sensor) if safety else None
        self.noise = noise
        self._clocks = tuple(SampleHoldDelay(noise.timing[s.name], 1.0 / control_hz) for s in self.sensors)
        self._action_channel = ActionChannel(noise.action, robot.action_space.shape[0])
        self._noise_rng = np.random.default_rng(0)  # replaced at every reset from np_random
        self.render_mode = render_mode
        self.render_size = render_size
        # render-only state, kept while a render_mode is set: where the robot's focus has been (the frames' trail)
        self._trail: deque[np.ndarray] = deque(maxlen=TRAIL_LENGTH)
        self._focus_radius = 0.0
        self.metadata = {**self.metadata, "render_fps": control_hz}
        self.substeps = int(round(sim.physics_hz / control_hz))  # physics ticks per action
        self._control_hz = control_hz
        self._auto_physics = physics == "auto"
        self.physics = PhysicsChoice(sim.physics_hz, solver_iterations, "the env's settings (physics='fixed')")
        self._base_physics = self.physics
        # a TickedRobot (interfaces.py) acts before every physics tick; others once per action
        self._before_tick = cast(TickedRobot, robot).before_tick if getattr(robot, "ticked", False) else None
        self._build_world()
        self.action_space = robot.action_space
        self._action_low = self.action_space.low.astype(np.float64)
        self._action_high = self.action_space.high.astype(np.float64)
        self.observation_space = spaces.Dict(
            {**{key: space for s in self.sensors for key, space in s.spaces.items()}, **task.spaces, **robot.spaces}
        )
        self.scene: Layout | None = None  # None between episodes: before the first reset and after a failed one
        self._failed_reset: str | None = None  # why the last reset raised, until one succeeds
        self._movable: tuple[np.ndarray, list[int]] = (np.zeros(0, dtype=int), [])  # scene indices and bodies

    @property
    def movable_bodies(self) -> list[int]:
        """pybullet body ids of this episode's movable obstacles, in scene order."""
        return self._movable[1]

    def _build_world(self) -> None:
        """Load the arena, the robot and the goal marker into the (empty) Sim."""
        self.arena.load(self.sim)
        self.robot.load(self.sim)
        self._goal_marker = self.sim.add_marker("goal", self.task.success_radius, (0.1, 0.8, 0.2, 0.9))

    # ------------------------------------------------------------------------------------------ episode
    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start an episode on a new seeded layout, or on ``options["scene"]`` (format: docs/envs.md,
        "Scene format").

        A reset that raises leaves no episode: the world may hold part of the refused scene, so :meth:`step`
        refuses to run until a reset succeeds.

        Raises:
            RuntimeError: the env is closed.
            ValueError: ``options`` or its scene is invalid, or a user scene starts in collision.
        """
        self._check_open()
        try:
            return self._reset(seed, options)
        except BaseException as error:
            self.scene, self._failed_reset = None, f"{type(error).__name__}: {error}"
            raise

    def _reset(self, seed: int | None, options: Mapping[str, Any] | None
               ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        scene = self.arena.choose_scene(self.np_random, options)
        self._choose_physics(scene)
        if self.sim.needs_rebuild:  # memory pybullet only frees by emptying the world: build it again
            self.sim.clear()
            self._build_world()
        # Noise draws come from a generator seeded by one draw of np_random, taken whatever the profile: the
        # layouts of a seed are then the same under every noise profile (paired sim-to-real comparisons).
        self._noise_rng = rng = np.random.default_rng(int(self.np_random.integers(2**63)))
        self.robot.apply_dynamics(sample_dynamics(rng, self.noise.dynamics))
        obstacles, bodies = self.arena.place(scene)
        self.checker.set_scene(obstacles, bodies)
        movable = [i for i, o in enumerate(obstacles) if o.movable]
        self._movable = (np.array(movable, dtype=int), [bodies[i] for i in movable])
        self.robot.reset_to(scene.start)
        self.sim.move_static(self._goal_marker, self.task.marker_position(scene), yaw_quat(0.0))
        self.scene = scene
        state = self.robot.state()
        self._note_focus(state, restart=True)
        for sensor, clock in zip(self.sensors, self._clocks):
            sensor.reset(self.sim, state, rng)
            clock.reset(rng)
        self._action_channel.reset()
        if self.safety:
            self.safety.reset()
        self.task.reset(scene, state)
        report = self.checker.check(state, self.sim.contact_distances(self.robot.body))
        self._check_start(report, options)
        self._follow(state)
        obs, info = self._observe(state, report)
        info.update(
            min_clearance=report.min_clearance, n_contacts=report.n_contacts, is_success=False,
            noise_profile=self.noise.name, physics=self.physics.as_info(),
        )
        self._failed_reset = None
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """Apply one action for one control period.

        Raises:
            ValueError: the action has the wrong shape or holds NaN/Inf. Finite values outside [-1, 1] are
                clipped, not rejected.
            RuntimeError: the env is closed, was never reset, or its last reset failed.
        """
        self._check_open()
        if self.scene is None:
            if self._failed_reset is not None:
                raise RuntimeError(f"the last reset() failed ({self._failed_reset}); call reset() again before step()")
            raise RuntimeError("call reset() before step()")
        a = self._command(self._checked_action(action))
        if self.safety:
            assert self._scan is not None  # every reset delivers a reading of the filter's sensor
            applied, speed_scale = self.safety.filter(a, self._scan)
        else:
            applied, speed_scale = a, 1.0
        command = self._action_channel.send(applied, self._noise_rng)
        if command is not applied:
            command = np.minimum(np.maximum(command, self._action_low), self._action_high)
        self.robot.apply_action(command)
        if self._before_tick is None:
            self.sim.step(self.substeps)
        else:
            for _ in range(self.substeps):
                self._before_tick()
                self.sim.step()
        if self._movable[1]:  # the checker follows what the physics pushed
            self.checker.move_obstacles(self._movable[0], *self.sim.body_poses(self._movable[1]))
        state = self.robot.state()
        self._note_focus(state)
        report = self.checker.check(state, self.sim.contact_distances(self.robot.body))
        self._follow(state)
        obs, info = self._observe(state, report)
        outcome = self.task.evaluate(state, report, a)
        info.update(
            reward_terms=outcome.terms,
            cost=outcome.cost,
            **{f"cost_{cause}": value for cause, value in outcome.costs.items()},
            is_success=outcome.is_success,
            **report.as_info(),
        )
        if self.safety:
            info["safety_scale"] = speed_scale
            info["safety_recovery"] = self.safety.recovering
        if not math.isfinite(outcome.reward):
            raise FloatingPointError(f"non-finite reward {outcome.reward} from terms {outcome.terms}")
        if self.render_mode == "human":
            self.render()
        return obs, float(outcome.reward), outcome.terminated, False, info

    def _follow(self, state: RobotState) -> None:
        """In a large scene (``worlds/near_field.py``), make every obstacle the robot could touch in the next step a
        body: those within the ball of the robot's shapes (synced by the last check) grown by twice the distance its
        fastest point covers in a step at the speeds of ``state``."""
        if not self.arena.near_field_engaged:
            return
        centre, reach = self.checker.model.bounding_ball()
        linear = np.vstack((state.linear_velocity, state.links.linear_velocity))
        angular = np.vstack((state.angular_velocity, state.links.angular_velocity))
        speed = math.sqrt(float((linear * linear).sum(axis=1).max()))
        speed += math.sqrt(float((angular * angular).sum(axis=1).max())) * reach
        bodies = self.arena.follow(centre, reach + 2.0 * speed / self._control_hz)
        if bodies is not None:
            self.checker.set_obstacle_bodies(bodies)

    def _choose_physics(self, scene: Layout) -> None:
        """Under ``physics="auto"``, tick this episode at what ``scene`` needs (the env's own settings unless it
        needs more)."""
        if not self._auto_physics:
            return
        base = self._base_physics
        self.physics = chosen = choose_physics(scene.obstacles, base.physics_hz, base.solver_iterations,
                                               self._control_hz)
        if (chosen.physics_hz, chosen.solver_iterations) != (self.sim.physics_hz, self.sim.solver_iterations):
            self.sim.set_physics(chosen.physics_hz, chosen.solver_iterations)
            self.substeps = int(round(chosen.physics_hz / self._control_hz))

    def _command(self, action: np.ndarray) -> np.ndarray:
        """The normalised command the robot is to drive for a checked policy action (the action itself; an env
        whose actions map onto commands another way overrides it). The monitor, the action noise and the reward
        all see the command."""
        return action

    def _checked_action(self, action: Any) -> np.ndarray:
        """``action`` as float64 within the bounds: any real dtype and container of the right shape, clipped, and an
        object array whose every element is a real number (Python's, numpy's, a Fraction); anything else (strings,
        None, bools, complex numbers, NaN, Inf) is a ``ValueError`` naming the action."""
        shape = self._action_low.shape
        try:
            a = np.asarray(action)
        except ValueError:  # ragged nesting
            a = np.empty(0, dtype=object)
        if a.dtype.kind == "O" and a.size and all(is_number(v) for v in a.flat):
            try:
                a = a.astype(np.float64)
            except OverflowError:  # an integer beyond the float range
                raise ValueError(f"action must be finite (no NaN/Inf), got {repr(action)[:200]}") from None
        if a.dtype.kind not in "fiu":
            raise ValueError(f"action must be {shape[0]} real numbers (floats or integers), got {repr(action)[:200]}")
        a = a.astype(np.float64, copy=False)
        if a.shape != shape:
            raise ValueError(f"action must have shape {shape}, got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"action must be finite (no NaN/Inf), got {a.tolist()}")
        return np.minimum(np.maximum(a, self._action_low), self._action_high)

    def _check_start(self, report: CollisionReport, options: Mapping[str, Any] | None) -> None:
        """Refuse a user scene that starts in collision: a contact, or self-collision of a pair the ACM checks (at a
        coarse level confirmed with the convex shapes, so the robot's own, not its coarse shapes').

        A generated scene is not checked: its sampler keeps the clutter clear of the start pose, and it starts clear
        at every fidelity level, so it is accepted back as a user scene (tests/test_reach.py checks every level and a
        padded arm: padding is a margin against the world, and self-collision is judged unpadded)."""
        if options and "scene" in options and (report.in_contact or report.self_collision is not None):
            what = report.contacts[0] if report.contacts else f"self-collision {report.self_collision}"
            raise ValueError(f"scene starts in collision: {what}")

    def _observe(self, state: RobotState, report: CollisionReport) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        obs: dict[str, np.ndarray] = {}
        info: dict[str, Any] = {}
        for sensor, clock in zip(self.sensors, self._clocks):
            sensor_obs, sensor_info, reading = timed_reading(sensor, clock, self.sim, state, self._noise_rng)
            obs.update(sensor_obs)
            info.update(sensor_info)
            if sensor is self._scan_from:
                self._scan = reading
        obs.update(self.task.observe(state, report))
        obs.update(self.robot.observe(state))
        floats = [v for v in obs.values() if v.dtype.kind == "f"]  # integer images cannot hold NaN/Inf
        if not math.isfinite(sum(float(v.sum()) for v in floats)):  # NaN/Inf anywhere poisons the sum
            bad = [key for key, value in obs.items() if not np.all(np.isfinite(value))]
            raise FloatingPointError(f"non-finite observation {bad}: {[obs[k] for k in bad]}")
        return obs, info

    # ---------------------------------------------------------------------------------------- rendering
    def render(self) -> np.ndarray | None:
        """rgb_array: the view of :meth:`render_view` (H, W, 3) uint8, with the robot and the goal ringed and the
        robot's recent trail drawn (:func:`clutter_gym.util.overlay.draw_marks`); human: points the GUI camera
        the same way. Rendering reads the world and draws nothing into it: it never changes a trajectory."""
        self._check_open()
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode= to gym.make")
            return None
        view = self.render_view()
        if self.render_mode == "human":
            self.sim.follow_camera(view.target, *orbit_angles(view.eye, view.target))
            return None
        frame = self.sim.render(view.width, view.height, view.eye, view.target, view.fov_deg)
        focus, goal = self._focus_and_goal()
        return draw_marks(frame, view, (focus, self._focus_radius), (goal, self.task.success_radius), self._trail)

    def render_view(self) -> CameraView:
        """The camera of the next rgb_array frame, chosen by the arena (``Arena.render_camera``) from where the
        robot's focus and the goal are: for measuring things in its pixels."""
        focus, goal = self._focus_and_goal()
        eye, target = self.arena.render_camera(self.sim, focus, goal)
        width, height = self.render_size
        return CameraView((float(eye[0]), float(eye[1]), float(eye[2])),
                          (float(target[0]), float(target[1]), float(target[2])), width, height)

    def _note_focus(self, state: RobotState, restart: bool = False) -> None:
        """Remember where the robot's focus is, for the trail the frames draw; only while a render mode is set."""
        if self.render_mode is None:
            return
        if restart:
            self._trail.clear()
        centre, self._focus_radius = self.robot.render_focus(state)
        self._trail.append(np.array(centre, dtype=float))

    def _focus_and_goal(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's focus and the goal marker's centre, world frame (before the first reset: where the robot
        stands, for both; so too after a reset that failed, which left no scene)."""
        if not self._trail or self.scene is None:
            centre, self._focus_radius = self.robot.render_focus(self.robot.state())
            return np.asarray(centre, dtype=float), np.asarray(centre, dtype=float)
        return self._trail[-1], np.asarray(self.task.marker_position(self.scene), dtype=float)

    def close(self) -> None:
        """Disconnect the physics client; safe to call twice. The env cannot step, reset or render after it."""
        self.sim.close()

    def __reduce_ex__(self, protocol: Any) -> Any:
        """Refuse pickling and copying (``pickle``, ``copy.copy``, ``copy.deepcopy``, cloudpickle) with a message that
        names the env: it owns a pybullet physics client and FCL objects, which cannot be serialised, and a shallow
        copy would share them. Raises TypeError."""
        name = f"{self.spec.id} ({type(self).__name__})" if self.spec is not None else type(self).__name__
        raise TypeError(
            f"{name} cannot be pickled or copied: it owns a pybullet physics client and FCL collision objects. Make "
            f"a new env instead, with gym.make and the same id and kwargs, and reset it with the same seed; for a "
            f"vector env pass a factory (e.g. lambda: gym.make(...)) rather than an env"
        )

    def _check_open(self) -> None:
        if self.sim.client_id < 0:
            name = self.spec.id if self.spec is not None else type(self).__name__
            raise RuntimeError(f"{name} is closed: make a new env with gym.make")






def collision_checker(robot: Robot, tracked_links: Sequence[str], fidelity: str, padding: float,
                      contact_tolerance: float, clearance_range: float, control_hz: float, *,
                      self_collision: bool = True, swept_speed: float = 0.2,
                      fixed_links: Sequence[str] = (), per_link: bool = True) -> CollisionChecker:
    """The FCL model of ``robot`` (its base and ``tracked_links``) at ``fidelity``, and its checker, which sweeps
    links between two control steps (``per_link=False``: one that measures only the robot's nearest pair).

    Raises:
        ValueError: an unknown fidelity level, or a padding outside [0, 1] metres.
    """
    model = RobotCollisionModel.from_urdf(robot.urdf_path, check_fidelity(fidelity),
                                          (robot.base_link, *tracked_links), padding, self_collision)
    return CollisionChecker(model, base_link=robot.base_link, contact_tolerance=contact_tolerance,
                            clearance_range=clearance_range, swept_speed=swept_speed, dt=1.0 / control_hz,
                            fixed_links=fixed_links, per_link=per_link)


def _sensor_named(sensors: Sequence[Sensor], name: str) -> Sensor:
    """The sensor called ``name`` among ``sensors``.

    Raises:
        ValueError: none is (the message lists the sensors there are).
    """
    for sensor in sensors:
        if sensor.name == name:
            return sensor
    raise ValueError(f"the safety filter reads the {name!r} sensor; the env's sensors are {[s.name for s in sensors]}")
