"""Tunneling runs: a fast body launched at a thin wall, with pybullet alone or with pybullet's CCD on the fast body,
under the project's FCL audit; how each run ended, and which of them saw it.

The runs:

* a free cube or ball (size ``EDGE``) launched at a wall, the cube as a multibody (pybullet's default, for
  ``createMultiBody`` and ``loadURDF`` alike) or as a rigid body (``useMaximalCoordinates``), in a bare
  :class:`~clutter_gym.sim.Sim` at an env's physics rate, audited by a
  :class:`~clutter_gym.collision.CollisionChecker` of the body with that env's checker settings
  (:func:`free_body_run`);
* the ClutterNav-v1 robot (``assets/robots/diffbot.urdf``) launched along its heading with
  ``pybullet.resetBaseVelocity`` into a wall of a user scene, at zero command, in the env itself (:func:`nav_run`);
* the ClutterReach-v1 Panda at its full joint speed (``max_joint_speed`` at its maximum) bringing its hand down onto
  a shelf board or sideways into a shelf side, in the env itself (:data:`HAND_CASES`, :func:`hand_run`).

Whether a body tunnels depends on where the physics ticks fall against the wall, so a run starts from an offset
that callers spread over one tick's travel. At the end of a run the body is *inside* the wall when FCL finds it
deeper than ``EMBEDDED`` into it, else *through* when its centre (the Panda's end effector) is past the wall's
middle plane, else stopped; a run that ends through or inside is a *pass*.

pybullet's contacts are read after every physics tick (the envs step through ``Sim.step``, which a wrapper on the
env's Sim replaces for the run). CCD is ``changeDynamics(body, link, ccdSweptSphereRadius=r,
contactProcessingThreshold=0)`` on every link of the moving body, ``r`` well inside the link (pybullet then sweeps
a link that moves more than half of ``r`` in a tick). The audit has *flagged* a run when, in any control step, the
end-of-step check found a contact (``info["n_contacts"]``) or the swept check a hit (``info["tunneling"]``): a
shape that moved faster than ``swept_speed`` over the control period is swept from its previous pose, translation
only, and a hit the end-of-step check does not see counts. Everything is seeded and deterministic.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from clutter_gym.collision import CollisionChecker, CollisionElement, RobotCollisionModel, build_link_shapes
from clutter_gym.datatypes import LinkStates, Obstacle, RobotState
from clutter_gym.robots.panda import READY
from clutter_gym.sim import Sim, pb

GAP = 0.01  # the nearest start leaves this much between body and wall, metres
EMBEDDED = 0.01  # deeper into the wall than this at the end of a run: inside it, metres
LAUNCH_STEPS = 4  # control steps a launched body runs
HAND_STEPS = 8  # control steps the Panda runs
EDGE, MASS = 0.1, 1.0  # the free bodies: a cube's edge and a ball's diameter (m), mass (kg)
WALL_SPAN, WALL_HEIGHT = 2.0, 1.0  # the free bodies' wall, metres
NAV_ARENA, NAV_WALL_X = 10.0, -3.0  # a large arena: the arena walls stay out of reach of a run
NAV_WALL_HEIGHT = 0.5  # metres
CCD_RADIUS = {"free body": 0.025, "nav robot": 0.01, "Panda hand": 0.005}  # swept-sphere radii, metres
SIDE_START = (0.0, 0.3, 0.0, -1.2, 0.0, 1.5, math.pi / 4)  # arm stretched out, hand pointing down
SIDE_RADIUS, SIDE_ANGLE = 0.64, 0.35  # the shelf side: distance from the base axis (m) and bearing (rad)
SHELF_BOARD_Z = 0.36  # the shelf board's underside at the nearest offset, metres


@dataclass(frozen=True)
class Run:
    """One run: how it ended, and who saw it.

    Attributes:
        outcome: "through", "inside" or "stopped".
        pybullet_contact: pybullet reported a contact point between body and wall after some physics tick.
        fcl_contact: the audit's end-of-step check found a contact in some control step.
        swept_hits: the audit's swept hits over the run.
        peak_speed: fastest speed of the body (the Panda's hand) at the control steps, m/s.
    """

    outcome: str
    pybullet_contact: bool
    fcl_contact: bool
    swept_hits: int
    peak_speed: float

    @property
    def passed(self) -> bool:
        return self.outcome != "stopped"

    @property
    def flagged(self) -> bool:
        return self.fcl_contact or self.swept_hits > 0


@dataclass(frozen=True)
class Settings:
    """An env's physics rate and its audit's settings."""

    physics_hz: float
    substeps: int
    contact_tolerance: float
    swept_speed: float
    dt: float

    @classmethod
    def of(cls, env: gym.Env) -> Settings:
        u = env.unwrapped
        c = u.checker
        return cls(u.sim.physics_hz, u.substeps, c.contact_tolerance, c.swept_speed, c.dt)

    def describe(self) -> str:
        return (f"{self.physics_hz:.0f} Hz physics, {self.substeps} ticks per control step of {1000 * self.dt:.0f} ms; "
                f"swept check above {self.swept_speed} m/s, contact tolerance {1000 * self.contact_tolerance:.0f} mm")


def outcome(penetration: float, past: bool) -> str:
    if penetration > EMBEDDED:
        return "inside"
    return "through" if past else "stopped"


@contextlib.contextmanager
def watch_contacts(sim: Sim, body: int, other: int) -> Iterator[list[bool]]:
    """Replace ``sim.step`` for the block with one that records, after every physics tick, whether ``body`` and
    ``other`` have a pybullet contact point."""
    seen: list[bool] = []
    cid = sim.client_id

    def step(n: int = 1) -> None:
        for _ in range(n):
            pb.stepSimulation(physicsClientId=cid)
            seen.append(bool(pb.getContactPoints(bodyA=body, bodyB=other, physicsClientId=cid)))

    sim.step = step
    try:
        yield seen
    finally:
        del sim.step


def enable_ccd(sim: Sim, body: int, radius: float) -> None:
    """pybullet's CCD on every link of ``body`` (the base included)."""
    cid = sim.client_id
    for link in range(-1, pb.getNumJoints(body, physicsClientId=cid)):
        pb.changeDynamics(body, link, ccdSweptSphereRadius=radius, contactProcessingThreshold=0.0,
                          physicsClientId=cid)


def body_at(sim: Sim, centre: Sequence[float]) -> int:
    """The body whose base sits at ``centre`` (a static obstacle the env placed)."""
    for body in sim.body_ids():
        position, _ = pb.getBasePositionAndOrientation(body, physicsClientId=sim.client_id)
        if np.allclose(position, centre, atol=1e-6):
            return body
    raise LookupError(f"no body at {list(centre)}")


# ------------------------------------------------------------------------------------------------ free bodies
def body_checker(shape: str, settings: Settings) -> CollisionChecker:
    """The audit of a free body (``shape`` "cube" or "ball"): its FCL shape, with an env's checker settings."""
    kind, size = ("box", (EDGE, EDGE, EDGE)) if shape == "cube" else ("sphere", (0.5 * EDGE,))
    element = CollisionElement(shape, kind, size, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))
    model = RobotCollisionModel(build_link_shapes([element], "primitive"), (shape,))
    return CollisionChecker(model, shape, contact_tolerance=settings.contact_tolerance,
                            swept_speed=settings.swept_speed, dt=settings.dt)


def body_state(sim: Sim, body: int) -> RobotState:
    position, rotation, linear, angular = sim.base_state(body)
    none = LinkStates(np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    return RobotState(np.asarray(position), np.reshape(rotation, (3, 3)), linear, angular, none, (), {}, body)


def free_body_run(settings: Settings, shape: str, speed: float, thickness: float, offset: float, *, rigid: bool,
                  ccd: bool) -> Run:
    """A free body (``shape`` "cube" or "ball") launched along +x from ``offset`` metres before a wall ``thickness``
    thick; ``rigid``: a rigid body rather than a multibody; ``ccd``: with pybullet's CCD."""
    sim = Sim(physics_hz=settings.physics_hz)
    try:
        cid = sim.client_id
        wall = Obstacle("box", (thickness, WALL_SPAN, WALL_HEIGHT), (0.0, 0.0))
        (wall_body,) = sim.obstacles.add_static_boxes([0.5 * s for s in wall.size], (0.5, 0.5, 0.5, 1.0), [wall.centre])
        if shape == "cube":
            collision = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.5 * EDGE] * 3, physicsClientId=cid)
        else:
            collision = pb.createCollisionShape(pb.GEOM_SPHERE, radius=0.5 * EDGE, physicsClientId=cid)
        start = (-0.5 * thickness - 0.5 * EDGE - offset, 0.0, wall.centre[2])
        body = pb.createMultiBody(MASS, collision, -1, start, useMaximalCoordinates=rigid, physicsClientId=cid)
        if ccd:
            enable_ccd(sim, body, CCD_RADIUS["free body"])
        pb.resetBaseVelocity(body, [speed, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=cid)
        checker = body_checker(shape, settings)
        checker.set_scene([wall], [wall_body])
        report = checker.check(body_state(sim, body))
        fcl_contact, hits = False, 0
        with watch_contacts(sim, body, wall_body) as seen:
            for _ in range(LAUNCH_STEPS):
                sim.step(settings.substeps)
                report = checker.check(body_state(sim, body), sim.contact_distances(body))
                fcl_contact, hits = fcl_contact or report.in_contact, hits + report.tunneling
        x = body_state(sim, body).position[0]
        return Run(outcome(-report.min_clearance, x > 0.0), any(seen), fcl_contact, hits, speed)
    finally:
        sim.close()


# ------------------------------------------------------------------------------------------------ nav robot
def make_nav_env() -> gym.Env:
    return gym.make("ClutterNav-v1", arena_size=NAV_ARENA, sensors=())


def nav_run(env: gym.Env, speed: float, thickness: float, offset: float, *, ccd: bool) -> Run:
    """The robot launched along its heading (+x) from ``offset`` metres before a wall ``thickness`` thick."""
    u = env.unwrapped
    radius = u.robot.config.footprint_radius  # the chassis cylinder's radius
    wall = {"shape": "box", "size": [thickness, WALL_SPAN, NAV_WALL_HEIGHT], "position": [NAV_WALL_X, 0.0]}
    start = [NAV_WALL_X - 0.5 * thickness - radius - offset, 0.0, 0.0]
    env.reset(seed=0, options={"scene": {"obstacles": [wall], "start": start, "goal": [0.4 * NAV_ARENA, 0.0]}})
    sim, body = u.sim, u.robot.body
    if ccd:
        enable_ccd(sim, body, CCD_RADIUS["nav robot"])
    pb.resetBaseVelocity(body, [speed, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=sim.client_id)
    fcl_contact, hits, depth = False, 0, 0.0
    with watch_contacts(sim, body, body_at(sim, (NAV_WALL_X, 0.0, 0.5 * NAV_WALL_HEIGHT))) as seen:
        for _ in range(LAUNCH_STEPS):
            _, _, terminated, _, info = env.step(np.zeros(2, dtype=np.float32))
            fcl_contact, hits = fcl_contact or info["n_contacts"] > 0, hits + info["tunneling"]
            depth = info["max_penetration"]
            if terminated:
                break
    x = u.robot.state().position[0]
    return Run(outcome(depth, x > NAV_WALL_X), any(seen), fcl_contact, hits, speed)


# ------------------------------------------------------------------------------------------------ Panda hand
Board = tuple[dict, np.ndarray, np.ndarray]  # a scene obstacle, its centre, the direction the hand crosses it in


def shelf_board(thickness: float, offset: float) -> Board:
    """A horizontal board under the hand in the ready pose, raised by ``offset`` metres."""
    z = SHELF_BOARD_Z + offset
    return ({"shape": "box", "size": [0.3, 0.6, thickness], "position": [0.35, 0.0], "z": z},
            np.array([0.35, 0.0, z + 0.5 * thickness]), np.array([0.0, 0.0, -1.0]))


def shelf_side(thickness: float, offset: float) -> Board:
    """An upright board across the path of the stretched-out hand turning about the base, moved ``offset`` metres
    towards it."""
    angle = SIDE_ANGLE - offset / SIDE_RADIUS
    c, s = math.cos(angle), math.sin(angle)
    return ({"shape": "box", "size": [0.16, thickness, 0.2], "position": [SIDE_RADIUS * c, SIDE_RADIUS * s],
             "yaw": angle, "z": 0.45}, np.array([SIDE_RADIUS * c, SIDE_RADIUS * s, 0.55]), np.array([-s, c, 0.0]))


@dataclass(frozen=True)
class HandCase:
    """A Panda motion at full joint speed (start pose, action) and the board in its way."""

    name: str
    start: tuple[float, ...]
    action: tuple[float, ...]
    board: Callable[[float, float], Board]


HAND_CASES = (
    HandCase("down onto a shelf board", READY, (0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0), shelf_board),
    HandCase("sideways into a shelf side", SIDE_START, (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), shelf_side),
)


def make_reach_env() -> gym.Env:
    return gym.make("ClutterReach-v1", max_joint_speed=1.0, n_obstacles=0, shelf=False)


def hand_run(env: gym.Env, case: HandCase, thickness: float, offset: float, *, ccd: bool) -> Run:
    """The Panda's motion ``case`` against its board ``thickness`` thick, moved ``offset`` metres towards the hand."""
    u = env.unwrapped
    board, centre, direction = case.board(thickness, offset)
    env.reset(seed=0, options={"scene": {"obstacles": [board], "start": list(case.start), "target": [0.4, -0.3, 0.5]}})
    sim, body = u.sim, u.robot.body
    if ccd:
        enable_ccd(sim, body, CCD_RADIUS["Panda hand"])
    hand, ee = u.robot.link_names.index("panda_hand"), u.robot.link_names.index("panda_grasptarget")
    action = np.array(case.action, dtype=np.float32)
    fcl_contact, hits, depth, peak = False, 0, 0.0, 0.0
    with watch_contacts(sim, body, body_at(sim, centre)) as seen:
        for _ in range(HAND_STEPS):
            _, _, _, _, info = env.step(action)
            fcl_contact, hits = fcl_contact or info["n_contacts"] > 0, hits + info["tunneling"]
            depth = info["max_penetration"]
            peak = max(peak, float(np.linalg.norm(u.robot.state().links.linear_velocity[hand])))
    past = float(np.dot(u.robot.state().links.position[ee] - centre, direction)) > 0.0
    return Run(outcome(depth, past), any(seen), fcl_contact, hits, peak)
