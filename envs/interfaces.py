"""The contracts between :class:`clutter_gym.core.ClutterEnv` and its parts: robot, arena, task and sensor.

They are structural (``typing.Protocol``): a part never inherits from them, it only has the members. ``core.py``
is typed against these and nothing else, so a new robot, world or task is a new module that has these members
(docs/architecture.md walks through adding one). Frames: world z up, metres, radians; quaternions are
(x, y, z, w) everywhere, as pybullet returns them.

The scene is the one value the arena and the task of an env must agree on: the arena draws it (or parses the
user's ``options["scene"]``), the robot starts at ``scene.start``, and the task reads its goal from it.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

from clutter_gym.datatypes import CollisionReport, DynamicsSample, Obstacle, RobotState, StepOutcome

if TYPE_CHECKING:  # names in signatures only: importing this module loads no engine
    import numpy as np
    from gymnasium.spaces import Box, Space

    from clutter_gym.sim import Sim


class Layout(Protocol):
    """One episode's scene (plain, frozen data): obstacles, the robot's start, and the task's goal fields.

    ``start`` is whatever :meth:`Robot.reset_to` takes: (x, y, yaw) for a mobile base, joint positions for an
    arm. ``to_dict()`` gives the ``options["scene"]`` form that reproduces the scene.
    """

    @property
    def obstacles(self) -> tuple[Obstacle, ...]: ...

    @property
    def start(self) -> tuple[float, ...]: ...

    def to_dict(self) -> dict[str, Any]: ...


#: An env's layout type: its arena draws that type and its task reads it (a type checker holds the two to one type).
L = TypeVar("L", bound=Layout)
L_contra = TypeVar("L_contra", bound=Layout, contravariant=True)


class Robot(Protocol):
    """A URDF robot: loads itself into the world, maps normalised actions to motor commands, reads its state.

    Attributes:
        name: short name, used in asset and cache paths.
        urdf_path: the robot's URDF (its collision geometry builds the FCL model).
        base_link: the URDF's root link (its pose is ``RobotState.position`` / ``rotation``).
        action_space: the env's action space (``Box(-1, 1, ...)``).
        spaces: the observation entries :meth:`observe` fills.
        body: pybullet body id once loaded.
        link_names: the links :meth:`state` reads every step, the rows of ``RobotState.links``; set by :meth:`load`.
        link_index: pybullet index of every link by URDF name (-1 for the base); set by :meth:`load`.
    """

    @property
    def name(self) -> str: ...

    @property
    def base_link(self) -> str: ...

    @property
    def action_space(self) -> Box: ...

    @property
    def spaces(self) -> Mapping[str, Space]: ...

    @property
    def link_names(self) -> tuple[str, ...]: ...

    @property
    def link_index(self) -> Mapping[str, int]: ...

    @property
    def urdf_path(self) -> Path: ...

    @property
    def body(self) -> int: ...

    def load(self, sim: Sim) -> int:
        """Load the URDF into ``sim`` and look up joints and links; returns the body id. Called whenever the env
        builds its world: at construction, and again after :meth:`Sim.clear` (every earlier id is gone)."""

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """This episode's randomised masses, friction, restitution and motor strength."""

    def reset_to(self, start: tuple[float, ...]) -> None:
        """Teleport to ``scene.start`` at rest."""

    def apply_action(self, action: np.ndarray) -> None:
        """Set motor targets for one control period from a clipped, normalised action."""

    def state(self) -> RobotState:
        """Ground truth after a step, from batched pybullet reads."""

    def observe(self, state: RobotState) -> dict[str, np.ndarray]:
        """Proprioceptive observation entries."""

    def render_focus(self, state: RobotState) -> tuple[np.ndarray, float]:
        """(centre (3,), radius) in metres, world frame, of the part of the robot the ``rgb_array`` view marks,
        trails and keeps in sight: the base of a mobile robot, an arm's end effector."""


class TickedRobot(Robot, Protocol):
    """A robot that must act before every physics tick, not once per control step: one driven by external forces
    (a quadrotor's rotor thrusts), which pybullet clears after each ``stepSimulation``, or one whose inner loop runs
    at the physics rate.

    A robot opts in with the class attribute ``ticked = True``. The env's full physics
    (:class:`clutter_gym.dynamics.FullPhysics`) then runs the control period one tick at a time,
    ``robot.before_tick(); sim.step()``, after :meth:`Robot.apply_action`; robots without the attribute keep
    ``sim.step(substeps)``.
    """

    @property
    def ticked(self) -> bool: ...

    def before_tick(self) -> None:
        """Apply this tick's actuation (forces, motor targets) from the command :meth:`Robot.apply_action` held."""


class Arena(Protocol[L]):
    """The world around the robot: fixed structure built with the world, clutter moved into place per episode.

    Attributes:
        near_field: whether a large scene may keep its far static obstacles out of the physics world (they stay in
            the collision checker and in the Sim's primitives); the env sets it False when a sensor or renderer
            reads pybullet's bodies.
    """

    near_field: bool

    @property
    def near_field_engaged(self) -> bool:
        """Whether this episode's scene keeps far obstacles out of the physics world (call :meth:`follow`)."""

    def load(self, sim: Sim) -> None:
        """Build the fixed structure (walls, a table) in an empty world; like :meth:`Robot.load`, called again
        after :meth:`Sim.clear`."""

    def choose_scene(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> L:
        """The user's ``options["scene"]`` (validated: errors name the field) or a layout drawn from ``rng``."""

    def place(self, scene: L) -> tuple[tuple[Obstacle, ...], list[int]]:
        """Move pooled bodies into ``scene``; returns every obstacle (fixed structure included) and its body ids,
        in the same order (-1 for an obstacle without a body), for the collision checker."""

    def follow(self, centre: np.ndarray, radius: float) -> list[int] | None:
        """Make every obstacle within ``radius`` metres of ``centre`` a body before the next physics tick; returns
        the obstacle bodies (fixed structure included) when they changed, else None."""

    def render_camera(self, sim: Sim, robot: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(eye, target) in metres, world frame, of the ``rgb_array`` view (and of the GUI camera under
        ``render_mode="human"``) when the robot's focus (:meth:`Robot.render_focus`) is at ``robot`` and the goal
        marker at ``goal``: a view in which both can be made out. It may cast rays in ``sim`` (a camera pulled in
        front of an obstacle) but never changes the world."""


class Task(Protocol[L_contra]):
    """Turns ground truth (never noisy observations) into named reward terms, a cost and termination.

    Attributes:
        success_radius: metres; the goal marker's size.
        spaces: the observation entries :meth:`observe` fills (the goal, as the robot would know it).
    """

    @property
    def success_radius(self) -> float: ...

    @property
    def spaces(self) -> Mapping[str, Space]: ...

    def marker_position(self, scene: L_contra) -> tuple[float, float, float]:
        """Where the goal marker is drawn, world frame."""

    def reset(self, scene: L_contra, state: RobotState) -> None:
        """Start an episode on ``scene`` with the robot in ``state``."""

    def observe(self, state: RobotState, report: CollisionReport) -> dict[str, np.ndarray]:
        """Goal and clearance observation entries."""

    def evaluate(self, state: RobotState, report: CollisionReport, action: np.ndarray) -> StepOutcome:
        """Reward terms, cost and termination of the step that led to ``state`` with the agent's ``action``."""


class Sensor(Protocol):
    """A noisy reading in physical units, and its observation form.

    A sensor is a clean read of the world and a chain of pure noise functions (``clutter_gym.noise``); the env
    runs each sensor's sample-and-hold and delay line (:class:`clutter_gym.sensors.timing.SampleHoldDelay`).

    Attributes:
        name: the sensor's name in ``sensors=(...)`` and in the noise profile's timing.
        spaces: observation keys this sensor fills, with their spaces.
        read_every_step: the sensor must be read every control step even while its output is held (state that
            integrates over time, like the IMU's finite difference).
        renders: the sensor draws images of the world, so the Sim must give obstacles visual shapes.
        needs_bodies: the sensor reads pybullet's bodies (pybullet's rays or renderer), so every obstacle must be a
            body in the physics world; a large scene otherwise keeps its far obstacles out of it (the Sim's
            primitives still hold them for the exact caster and the ray-cast camera).
    """

    @property
    def name(self) -> str: ...

    @property
    def spaces(self) -> Mapping[str, Space]: ...

    @property
    def read_every_step(self) -> bool: ...

    @property
    def renders(self) -> bool: ...

    @property
    def needs_bodies(self) -> bool: ...

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        """Start an episode: draw per-episode errors (biases, gains) from ``rng``."""

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> Any:
        """Clean reading plus noise, in physical units. Never writes to the world."""

    def observe(self, reading: Any) -> dict[str, np.ndarray]:
        """Observation entries (normalised/clipped as documented by the env) from a reading."""

    def info(self, reading: Any) -> dict[str, Any]:
        """``info`` entries that carry the physical reading (may be empty)."""
