"""Translated worlds: a ClutterNav scene built from the env's own parts (Sim, obstacle pool, FCL checker, LIDAR) at
the origin or moved by an offset, and scenes of millimetre obstacles around the robot. The envs have no
world-offset option, so every obstacle, the arena walls and the robot pose move by the offset (the floor is an
infinite plane). What was measured with them, and why each tolerance is what it is, is in
tests/hard_cases/test_scale.py; ``python -m benchmarks.hard_cases.catalogue`` prints short versions of those figures.

Lengths are metres; tolerances named ``*_ULPS`` count units in the last place of the offset (:func:`ulps`).
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from clutter_gym.collision import CollisionChecker, collision_checker
from clutter_gym.collision.distance import signed_distance
from clutter_gym.datatypes import LinkStates, Obstacle, RobotState
from clutter_gym.robots import DiffDriveRobot
from clutter_gym.robots.diffdrive import TRACKED_LINKS, DiffDriveConfig
from clutter_gym.sensors.lidar import Lidar
from clutter_gym.sim import CYLINDER_SIDES, Sim, pb
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.util.transforms import quat_to_matrix, yaw_quat
from clutter_gym.worlds.floor.arena import arena_walls
from clutter_gym.worlds.pool import ObstaclePool

CHASSIS_RADIUS = DiffDriveConfig().footprint_radius  # the chassis cylinder encloses every other link from above

OFFSETS = (1e3, 1e4)
EXACT_ULPS = 20  # in ulps of the offset: FCL closed-form routines (sphere shapes)
CONTACT_ULPS = 20  # pybullet contact distances
POSE_ULPS = 20  # poses after a rollout; link frames
RAY_ULPS = 500  # LIDAR ranges
GJK_TOL = 1e-3  # FCL distances of cylinder shapes (GJK), metres, at any offset
EPA_TOL = 1e-5  # FCL penetration depths, metres
MM_TOL = 2e-5  # FCL against closed forms around millimetre obstacles (measured 5e-6), metres
MM_CONTACT_TOL = 1e-4  # pybullet's deepest contact against the closed form (measured 4.2e-5), metres

ARENA = 6.0
WHEEL_RADIUS = 0.05  # diffbot.urdf: base_link is on the wheel axle, this high above the floor
CASTER_RADIUS = 0.02
LIDAR_X = 0.05  # diffbot.urdf lidar_joint: the scan origin's x in base_link
SCENE = (
    Obstacle("box", (0.4, 0.6, 0.5), (CHASSIS_RADIUS + 0.2 - 0.005, 0.0)),  # 5 mm into the chassis at (0, 0, 0.3)
    Obstacle("cylinder", (0.3, 0.3, 0.5), (-0.5, 0.6)),
    Obstacle("box", (0.3, 0.2, 0.4), (-1.2, -0.9), 0.7),
    Obstacle("cylinder", (0.002, 0.002, 0.3), (1.0, 1.5)),
    Obstacle("box", (0.2, 0.2, 0.4), (2.0 + CHASSIS_RADIUS + 0.1, -2.0)),  # its face touches the chassis at (2, -2, 0)
    *arena_walls(ARENA, 0.5, 0.1),
)
HAND_POSES = ((0.0, 0.0, 0.3), (2.0, -2.0, 0.0), (-1.5, 1.5, 1.0))  # 5 mm in, touching, clear
_rng = np.random.default_rng(0)
POSES = HAND_POSES + tuple(map(tuple, np.c_[_rng.uniform(-2.7, 2.7, (200, 2)), _rng.uniform(-np.pi, np.pi, 200)]))
_FRAMES = UrdfKinematics(DiffDriveRobot().urdf_path).forward(np.zeros((1, 2)))  # wheels at 0, as reset_pose leaves them


def ulps(offset: float, n: int) -> float:
    return n * float(np.spacing(offset))


def shifted(o: Obstacle, offset: float) -> Obstacle:
    return Obstacle(o.shape, o.size, (o.position[0] + offset, o.position[1] + offset), o.yaw, o.z)


@dataclass
class World:
    """One scene in its own pybullet client, with the robot, its FCL checker and a LIDAR."""

    offset: float
    sim: Sim
    robot: DiffDriveRobot
    checker: CollisionChecker
    obstacles: tuple[Obstacle, ...]
    bodies: list[int]

    def place(self, x: float, y: float, yaw: float) -> None:
        """The robot at (x, y, yaw) of the untranslated scene, with fresh pybullet contacts."""
        self.robot.reset_pose(x + self.offset, y + self.offset, yaw)
        pb.performCollisionDetection(physicsClientId=self.sim.client_id)

    def exact_state(self, x: float, y: float, yaw: float) -> RobotState:
        """The robot's state at (x, y, yaw) of the untranslated scene, link frames from the URDF in float64."""
        rotation = quat_to_matrix(np.array(yaw_quat(yaw)))
        base = np.array([x + self.offset, y + self.offset, WHEEL_RADIUS])
        positions = np.array([base + rotation @ _FRAMES[name][0, :3, 3] for name in TRACKED_LINKS])
        rotations = np.array([rotation @ _FRAMES[name][0, :3, :3] for name in TRACKED_LINKS])
        still = np.zeros((len(TRACKED_LINKS), 3))
        return RobotState(base, rotation, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                          LinkStates(positions, rotations, still, still), TRACKED_LINKS, self.robot.link_index,
                          self.robot.body)

    def contacts(self) -> dict[tuple[int, int, int], tuple[int, float]]:
        """pybullet's robot contacts: (other body, robot link, other link) -> (points, deepest distance)."""
        out: dict[tuple[int, int, int], list[float]] = defaultdict(list)
        for c in pb.getContactPoints(bodyA=self.robot.body, physicsClientId=self.sim.client_id):
            out[(c[2], c[3], c[4])].append(c[8])
        return {key: (len(d), min(d)) for key, d in out.items()}


def build(offset: float, obstacles: tuple[Obstacle, ...] = SCENE, contact_tolerance: float = 1e-3) -> World:
    sim = Sim()
    sim.add_ground(visual_size=1.0)
    robot = DiffDriveRobot()
    robot.load(sim)
    moved = tuple(shifted(o, offset) for o in obstacles)
    bodies = ObstaclePool(sim).place(moved)
    checker = collision_checker(robot, TRACKED_LINKS, "primitive", 0.0, contact_tolerance, math.sqrt(2.0) * ARENA,
                                20.0, swept_speed=math.inf)  # poses jump: nothing to sweep
    checker.set_scene(moved, bodies)
    return World(offset, sim, robot, checker, moved, bodies)



def measure(world: World, pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple]:
    """FCL per shape at the exact pose: distances, nearest obstacles, witness points (untranslated), contacts."""
    state = world.exact_state(*pose)
    world.checker.sync(state)
    distance, other, points = world.checker.clearance()
    report = world.checker.check(state)
    contacts = tuple((c.link, c.obstacle, c.depth) for c in report.contacts)
    return distance, other, points - [world.offset, world.offset, 0.0], contacts


def read_placed(world: World, pose: tuple[float, float, float], lidar: Lidar) -> tuple[dict, np.ndarray, object]:
    """The robot placed at ``pose`` through pybullet: its contacts (:meth:`World.contacts`), the LIDAR's clean
    ranges (metres) and the checker's report."""
    world.place(*pose)
    state = world.robot.state()
    report = world.checker.check(state, world.sim.contact_distances(world.robot.body))
    return world.contacts(), lidar.read_clean(world.sim, state), report


def drive_into_box(world: World, steps: int = 40) -> list[tuple[np.ndarray, float, int, int]]:
    """``steps`` control steps (6 physics ticks each) of full command with a slight turn from 0.33 m in front of
    the scene's first box; per step the base position (untranslated, metres), yaw (rad), pybullet's and the
    checker's contact counts."""
    world.place(-0.5, 0.0, 0.0)
    run = []
    for _ in range(steps):
        world.robot.apply_action(np.array([1.0, 0.1]))
        world.sim.step(6)
        state = world.robot.state()
        report = world.checker.check(state, world.sim.contact_distances(world.robot.body))
        run.append((state.position - [world.offset, world.offset, 0.0], state.yaw, report.pybullet_contacts,
                    report.n_contacts))
    return run


ROD = 0.001  # radius of a 2 mm rod, metres
#: the 64-gon prism pybullet collides and casts rays against has the circle's area: its corners lie this far out
PRISM_CORNER = ROD * math.sqrt(2 * math.pi / (CYLINDER_SIDES * math.sin(2 * math.pi / CYLINDER_SIDES)))
CUBE = 0.001


def millimetre_scene(gap: float) -> tuple[Obstacle, ...]:
    """Around the robot at (0, 0, 0), each ``gap`` from it: a 2 mm rod ahead of the chassis on the LIDAR's forward
    beam, a 1 mm cube on the floor whose top edge faces the front caster (a 2 cm sphere 0.12 m ahead of the axle,
    on the floor) and a 1 mm cube at chassis height behind it."""
    edge = 0.12 + math.sqrt((CASTER_RADIUS + gap) ** 2 - (CASTER_RADIUS - CUBE) ** 2)  # the floor cube's near face
    return (
        Obstacle("cylinder", (2 * ROD, 2 * ROD, 0.3), (CHASSIS_RADIUS + gap + ROD, 0.0)),
        Obstacle("box", (CUBE, CUBE, CUBE), (edge + CUBE / 2, 0.0)),
        Obstacle("box", (CUBE, CUBE, CUBE), (-CHASSIS_RADIUS - gap - CUBE / 2, 0.0), 0.0, 0.07),
    )


def millimetre_pairs(world: World) -> tuple[tuple[int, int, int], ...]:
    """For each obstacle of :func:`millimetre_scene`: (the robot shape ``gap`` from it, as an index into the
    checker's model; the obstacle's index; the robot's pybullet link of that shape)."""
    links = [s.link for s in world.checker.model.shapes]
    caster = world.robot.link_index["front_caster"]
    return ((links.index("base_link"), 0, -1), (links.index("front_caster"), 1, caster),
            (links.index("base_link"), 2, -1))


def millimetre_errors(world: World, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """The robot at the origin of a :func:`millimetre_scene` ``gap`` world: FCL's signed distance of each pair of
    :func:`millimetre_pairs` less ``gap``, and where ``gap`` <= 0 pybullet's deepest contact of each pair less
    ``gap`` (empty where the robot is clear), metres."""
    world.place(0.0, 0.0, 0.0)
    world.checker.sync(world.exact_state(0.0, 0.0, 0.0))
    model, objects = world.checker.model, world.checker.search.obstacles
    pairs = millimetre_pairs(world)
    fcl = np.array([signed_distance(model.objects[i], objects[j])[0] - gap for i, j, _ in pairs])
    if gap > 0:
        return fcl, np.zeros(0)
    contacts = world.contacts()
    deepest = [min(d for (body, link, _), (_, d) in contacts.items() if body == world.bodies[j] and link == robot_link)
               for _, j, robot_link in pairs]
    return fcl, np.array(deepest) - gap
