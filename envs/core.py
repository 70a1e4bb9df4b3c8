"""ClutterEnv: a Gymnasium env composed of a Sim, a robot, an arena, sensors, a collision checker and a task.

It only wires the parts together and runs the step's skeleton (docs/architecture.md, "One step"); every decision
about physics, layout, sensing, collision or reward lives in the part that owns it, behind the contracts of
:mod:`clutter_gym.interfaces`, and every optional feature of the step is a stage (:mod:`clutter_gym.stages`) whose
hooks the core calls only where the env has it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from clutter_gym import make_checks as checks
from clutter_gym.auto_physics import PhysicsChoice
from clutter_gym.collision import CollisionChecker
from clutter_gym.datatypes import CollisionReport, RobotState
from clutter_gym.dynamics.base import DynamicsFactory, FullPhysics
from clutter_gym.interfaces import Arena, L, Layout, Robot, Sensor, Task
from clutter_gym.noise.dynamics import sample_dynamics
from clutter_gym.noise.profiles import NoiseProfile
from clutter_gym.sensors.timing import TimedSensors
from clutter_gym.sim import Sim
from clutter_gym.stages import Movables, RenderTrail, Stage, env_stages, hooks
from clutter_gym.util.camera_view import CameraView
from clutter_gym.util.transforms import yaw_quat


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
        render_mode: None, "rgb_array" or "human"; render_size: (width, height) of rgb_array frames in pixels.
        stages: the env module's own stages, in order (its command mapping, the collision monitor); the core adds
            those its other settings ask for (:func:`clutter_gym.stages.env_stages`).
        physics: "fixed" runs every episode at ``physics_hz`` and ``solver_iterations``; "auto" raises them for a
            scene that needs more (:func:`clutter_gym.auto_physics.choose_physics`), never lowers them, and says what
            it chose in the reset's ``info["physics"]``.
        dynamics: makes the part that moves the robot from the Sim and the robot (:mod:`clutter_gym.dynamics`);
            full physics when None. The reset's ``info["dynamics"]`` says what it runs the episode under.
    """

    metadata = {"render_modes": list(checks.RENDER_MODES), "render_fps": 20}
    arena: Arena[Any]  # and the task: of one layout type, which __init__'s signature holds them to
    task: Task[Any]

    def __new__(cls, *args: Any, **kwargs: Any) -> ClutterEnv:
        """Check the keyword arguments against the env's own before it is built: a misspelt one is named with the
        closest allowed name and the whole list, where Python would only say "unexpected keyword argument"."""
        checks.check_keywords(cls, kwargs)
        return super().__new__(cls)

    def __init__(self, physics_hz: float, solver_iterations: int, robot: Robot, arena: Arena[L],
                 sensors: Sequence[Sensor], checker: CollisionChecker, task: Task[L], control_hz: float,
                 noise: NoiseProfile, render_mode: str | None = None, render_size: tuple[int, int] = (320, 240),
                 stages: Sequence[Stage] = (), physics: str = "fixed",
                 dynamics: DynamicsFactory | None = None) -> None:
        self.sensors = tuple(sensors)
        # an env that never draws gives its obstacles no visual shapes (docs/design-notes.md#obstacle-visuals)
        visuals = render_mode is not None or any(s.renders for s in self.sensors)
        sim = Sim(physics_hz=physics_hz, solver_iterations=solver_iterations, gui=render_mode == "human",
                  visuals=visuals)
        self.sim, self.robot, self.arena, self.checker, self.task = sim, robot, arena, checker, task
        # a large scene keeps its far obstacles out of the physics unless something reads every body
        arena.near_field = not visuals and not any(s.needs_bodies for s in self.sensors)
        self.noise = noise
        self.timed_sensors = TimedSensors(self.sensors, noise.timing, 1.0 / control_hz)
        self._noise_rng = np.random.default_rng(0)  # replaced at every reset from np_random
        self.render_mode, self.render_size = render_mode, render_size
        self.metadata = {**self.metadata, "render_fps": control_hz}
        self.control_hz = control_hz
        self.substeps = int(round(sim.physics_hz / control_hz))  # physics ticks per action
        self.physics = PhysicsChoice(sim.physics_hz, solver_iterations, "the env's settings (physics='fixed')")
        self.dynamics = FullPhysics(sim, robot) if dynamics is None else dynamics(sim, robot)
        self._build_world()
        self.action_space = robot.action_space
        self._bounds = (self.action_space.low.astype(np.float64), self.action_space.high.astype(np.float64))
        self.observation_space = spaces.Dict({**{key: space for s in self.sensors for key, space in s.spaces.items()},
                                              **task.spaces, **robot.spaces})
        # drawn only while a render mode is set (and followed by the GUI's camera in "human"); render_view works without
        self.render_trail = RenderTrail(human=render_mode == "human")
        self.stages = env_stages(stages, noise.action, physics, arena.near_field,
                                 self.render_trail if render_mode is not None else None)
        for stage in (*self.stages, self.render_trail):
            stage.bind(self)
        self._movables = next(s for s in self.stages if isinstance(s, Movables))
        self._activate(self.stages)
        self.scene: Layout | None = None  # None between episodes: before the first reset and after a failed one
        self._failed_reset: str | None = None  # why the last reset raised, until one succeeds

    def _activate(self, stages: Sequence[Stage]) -> None:
        """Call the step hooks of ``stages`` (this episode's active ones), and no others."""
        self._command_hooks, self._actuate_hooks, self._physics_hooks, self._checked_hooks, self._info_hooks = (
            hooks(stages, name) for name in ("command", "actuate", "physics_done", "checked", "step_info"))

    def robot_state(self) -> RobotState:
        """The robot's state as the env's dynamics has it: read this, not ``robot.state()``, which reads pybullet's
        bodies, and a reduced dynamics model moves the robot without moving them."""
        return self.dynamics.state()

    @property
    def movable_bodies(self) -> list[int]:
        """pybullet body ids of this episode's movable obstacles, in scene order."""
        return self._movables.bodies

    def _build_world(self) -> None:
        """Load the arena, the robot and the goal marker into the (empty) Sim."""
        self.arena.load(self.sim)
        self.robot.load(self.sim)
        self._goal_marker = self.sim.add_marker("goal", self.task.success_radius, (0.1, 0.8, 0.2, 0.9))

    # ------------------------------------------------------------------------------------------ episode
    def reset(self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
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
        for stage in self.stages:
            stage.scene_chosen(scene)
        if self.sim.needs_rebuild:  # memory pybullet only frees by emptying the world: build it again
            self.sim.clear()
            self._build_world()
        # Noise draws come from a generator seeded by one draw of np_random, taken whatever the profile: the
        # layouts of a seed are then the same under every noise profile (paired sim-to-real comparisons).
        self._noise_rng = rng = np.random.default_rng(int(self.np_random.integers(2**63)))
        self.dynamics.apply_dynamics(sample_dynamics(rng, self.noise.dynamics))
        obstacles, bodies = self.arena.place(scene)
        self.checker.set_scene(obstacles, bodies)
        self.robot.reset_to(scene.start)
        self.sim.obstacles.move_static(self._goal_marker, self.task.marker_position(scene), yaw_quat(0.0))
        self.scene = scene
        dynamics = self.dynamics.episode_start(obstacles)
        state = self.dynamics.state()
        self.timed_sensors.reset(self.sim, state, rng)
        self._activate([s for s in self.stages if s.episode_start(obstacles, bodies, rng)])
        self.task.reset(scene, state)
        report = self.checker.check(state, self.dynamics.contacts())
        if options and "scene" in options:
            checks.check_start(report)
        self.dynamics.checked(report)
        for checked_hook in self._checked_hooks:
            checked_hook(state)
        obs, info = self._observe(state, report)
        info.update(min_clearance=report.min_clearance, n_contacts=report.n_contacts, is_success=False,
                    noise_profile=self.noise.name, physics=self.physics.as_info(), dynamics=dynamics)
        self._failed_reset = None
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
        a = checks.checked_action(action, *self._bounds)
        for command_hook in self._command_hooks:
            a = command_hook(a)
        command = a
        for actuate_hook in self._actuate_hooks:
            command = actuate_hook(command, self._noise_rng)
        self.dynamics.advance(command, self.substeps)
        for physics_hook in self._physics_hooks:
            physics_hook()
        state = self.dynamics.state()
        report = self.checker.check(state, self.dynamics.contacts())
        self.dynamics.checked(report)
        for checked_hook in self._checked_hooks:
            checked_hook(state)
        obs, info = self._observe(state, report)
        outcome = self.task.evaluate(state, report, a)
        info.update(reward_terms=outcome.terms, cost=outcome.cost, is_success=outcome.is_success,
                    **{f"cost_{cause}": value for cause, value in outcome.costs.items()}, **report.as_info())
        for info_hook in self._info_hooks:
            info_hook(info)
        if not math.isfinite(outcome.reward):
            raise FloatingPointError(f"non-finite reward {outcome.reward} from terms {outcome.terms}")
        return obs, float(outcome.reward), outcome.terminated, False, info

    def _observe(self, state: RobotState, report: CollisionReport) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        obs, info = self.timed_sensors.read(self.sim, state, self._noise_rng)
        obs.update(self.task.observe(state, report))
        obs.update(self.robot.observe(state))
        checks.check_finite(obs)
        return obs, info

    # ---------------------------------------------------------------------------------------- rendering
    def render(self) -> np.ndarray | None:
        """rgb_array: the view of :meth:`render_view` (H, W, 3) uint8, with the robot and the goal ringed and the
        robot's recent trail drawn; human: points the GUI camera the same way
        (:class:`clutter_gym.stages.RenderTrail`). Rendering never changes a trajectory."""
        self._check_open()
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode= to gym.make")
            return None
        return self.render_trail.frame(human=self.render_mode == "human")

    def render_view(self) -> CameraView:
        """The camera of the next rgb_array frame, chosen by the arena (``Arena.render_camera``) from where the
        robot's focus and the goal are: for measuring things in its pixels."""
        return self.render_trail.view()

    def close(self) -> None:
        """Disconnect the physics client; safe to call twice. The env cannot step, reset or render after it."""
        self.sim.close()

    def __reduce_ex__(self, protocol: Any) -> Any:
        """Refuse pickling and copying (``pickle``, ``copy``, cloudpickle): it owns a pybullet client and FCL objects,
        which cannot be serialised, and a shallow copy would share them. Raises TypeError naming the env."""
        raise TypeError(checks.not_picklable(self.spec.id if self.spec else None, type(self).__name__))

    def _check_open(self) -> None:
        if self.sim.client_id < 0:
            name = self.spec.id if self.spec is not None else type(self).__name__
            raise RuntimeError(f"{name} is closed: make a new env with gym.make")
