"""Motion planning for an arm in joint space on a known layout: clear configurations, goal configurations from
inverse kinematics, RRT-Connect between them, shortcutting.

The parts are the textbook ones: goal configurations from position-only inverse kinematics (damped least squares
on the numpy forward kinematics, from random seeds), RRT-Connect (Kuffner and LaValle, 2000) between the start and
those goals, random shortcutting. Every configuration is checked with the shapes the env checks contacts with
(FCL, the ``convex`` level by default): each moving link at least ``margin`` from every obstacle and the table, and
no self-collision among the pairs the allowed-collision matrix enables; edges are checked every ``RESOLUTION``
radians of the joint that moves most. The ClutterReach ``subgoal`` observation (which walks the path as a
:class:`~clutter_gym.planning.path.JointPath`) and the planner reference in ``clutter_gym.training.joint_planner``
both plan here.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from clutter_gym.collision import CollisionChecker, RobotCollisionModel
from clutter_gym.datatypes import Obstacle
from clutter_gym.planning.hand_pose import HandPose, approach_axis
from clutter_gym.planning.path import RESOLUTION
from clutter_gym.robots.arm_model import ArmModel
from clutter_gym.robots.panda import panda_model
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.worlds.table.spec import TABLE

#: Goal configurations put the end effector anywhere in this ball around the target (metres): well inside the
#: env's success radius, and far more IK solutions clear the clutter than at the exact point.
GOAL_BALL = 0.03
#: How far the approach configurations back the end effector away from a goal, metres.
APPROACH = 0.15
#: Times the planner starts over (new goals, new trees) before it gives up on a layout.
ATTEMPTS = 2


def point_jacobian(kinematics: UrdfKinematics, frames: dict[str, np.ndarray], point: np.ndarray,
                   moved_by: int = 7, n_joints: int = 7) -> np.ndarray:
    """Position Jacobians (n, 3, n_joints) of world points ``point`` (n, 3) fixed to a link that the first
    ``moved_by`` arm joints move, at the configurations whose link ``frames`` (from ``kinematics.forward``) are
    given; the arm's joints are the URDF's first ``n_joints`` moving ones.

    Column i is joint i's axis in world coordinates crossed with the lever from the joint to the point (a URDF
    child link frame sits on its joint); the columns of the joints beyond ``moved_by`` are zero.
    """
    columns = []
    for i, joint in enumerate(kinematics.joints[:n_joints]):
        f = frames[joint.child]
        moving = np.cross(f[:, :3, :3] @ joint.axis, point - f[:, :3, 3])
        columns.append(moving if i < moved_by else np.zeros_like(moving))
    return np.stack(columns, axis=-1)


class ConfigurationChecker:
    """Is a batch of arm configurations clear of a layout? One FK pass per batch, FCL per configuration.

    Args:
        fidelity: the collision fidelity of the robot's shapes (a ``collision_fidelity`` level).
        margin: least distance from every moving link to every obstacle, metres.
        arm: the arm (the Panda by default).
    """

    def __init__(self, fidelity: str = "convex", margin: float = 0.02, arm: ArmModel | None = None) -> None:
        self.arm = arm = arm or panda_model()
        self.lower, self.upper, self.n_joints = arm.lower, arm.upper, len(arm.arm_joints)
        self.hand = HandPose(arm)
        self.kinematics = self.hand.kinematics
        names = (arm.base_link, *arm.tracked_links)
        self.model = RobotCollisionModel.from_urdf(arm.urdf, fidelity, names)
        self.checker = CollisionChecker(self.model, base_link=arm.base_link, clearance_range=margin,
                                        fixed_links=(arm.base_link, *arm.fixed_links))
        self._names = names
        self.margin = margin
        self.checks = 0  # configurations checked since construction (the planner's work)

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """The layout to check against (the table is always added)."""
        self.checker.set_scene((*obstacles, TABLE), [])

    def frames(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Link frames (n, 4, 4) of arm configurations ``q`` (n, n_joints), fingers (if any) at their opening."""
        return self.hand.link_frames(q)

    def ee_positions(self, q: np.ndarray) -> np.ndarray:
        """End-effector positions (n, 3) of configurations ``q`` (n, n_joints)."""
        return self.frames(q)[self.arm.ee_link][:, :3, 3]

    def ee_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """End-effector positions (n, 3) and their position Jacobians (n, 3, n_joints) at configurations ``q``.

        Column i is the arm's joint i axis in world coordinates crossed with the lever from the joint to the end
        effector (a URDF child link frame sits on its joint), from the same one FK pass.
        """
        frames = self.frames(q)
        ee = frames[self.arm.ee_link][:, :3, 3]
        return ee, point_jacobian(self.kinematics, frames, ee, self.n_joints, self.n_joints)

    def clearance(self, q: np.ndarray) -> float:
        """Least distance (metres, negative in penetration, capped at ``margin``) from the moving links of one
        configuration ``q`` (n_joints,) to the layout."""
        f = self._stacked_frames(np.asarray(q)[None])[0]
        return self._clearance(f)

    def free(self, q: np.ndarray, stop_at_first: bool = True) -> np.ndarray:
        """Per configuration of ``q`` (n, n_joints): clear of the layout by ``margin`` and free of self-collision.

        With ``stop_at_first`` the configurations after the first blocked one are reported blocked unchecked
        (an edge is only as good as its worst point).
        """
        ok = np.zeros(len(q), dtype=bool)
        for k, f in enumerate(self._stacked_frames(q)):
            ok[k] = self._clearance(f) >= self.margin and self.model.self_collision() is None
            if not ok[k] and stop_at_first:
                break
        return ok

    def _stacked_frames(self, q: np.ndarray) -> np.ndarray:
        frames = self.frames(q)
        return np.stack([frames[name] for name in self._names], axis=1)  # (n, links, 4, 4)

    def _clearance(self, frames: np.ndarray) -> float:
        """Sync the FCL shapes to one configuration's link frames and measure it."""
        self.checks += 1
        self.model.sync(frames[:, :3, 3], frames[:, :3, :3])
        distance, _, _ = self.checker.clearance()
        return float(distance.min())


def inverse_kinematics(checker: ConfigurationChecker, target: np.ndarray, seeds: np.ndarray,
                       iterations: int = 20, damping: float = 0.05, tolerance: float = 0.005) -> np.ndarray:
    """Position-only IK from every seed (n, n_joints) at once towards ``target`` (3,) or one target per seed (n, 3);
    returns the configurations that converged within ``tolerance`` (m, n_joints).

    Damped least squares on the analytic Jacobian of the end-effector position, clamped to the joint
    limits after every update; the orientation is free (success in ClutterReach is a position).
    """
    q = np.clip(np.asarray(seeds, dtype=float), checker.lower, checker.upper)
    for _ in range(iterations):
        q = _dls_step(checker, q, target, damping)
    error = np.linalg.norm(checker.ee_positions(q) - target, axis=-1)
    return q[error <= tolerance]


def _dls_step(checker: ConfigurationChecker, q: np.ndarray, target: np.ndarray, damping: float = 0.05) -> np.ndarray:
    """One damped-least-squares update of configurations ``q`` (n, n_joints) towards end-effector ``target``."""
    p, jac = checker.ee_jacobian(q)
    error = target - p
    jjt = jac @ jac.transpose(0, 2, 1) + damping**2 * np.eye(3)
    step = (jac.transpose(0, 2, 1) @ np.linalg.solve(jjt, error[..., None]))[..., 0]
    return np.clip(q + np.clip(step, -0.3, 0.3), checker.lower, checker.upper)


def _steer(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    d = b - a
    norm = np.linalg.norm(d)
    return b if norm <= step else a + d * (step / norm)


def _edge_free(checker: ConfigurationChecker, a: np.ndarray, b: np.ndarray, resolution: float) -> bool:
    n = max(1, int(np.ceil(np.abs(b - a).max() / resolution)))
    points = a + (b - a) * (np.arange(1, n + 1) / n)[:, None]
    return bool(checker.free(points).all())


class _Tree:
    def __init__(self, roots: np.ndarray) -> None:
        self.q = [np.asarray(r, dtype=float) for r in roots]
        self.parent = [-1] * len(roots)

    def nearest(self, q: np.ndarray) -> int:
        return int(np.argmin(np.linalg.norm(np.asarray(self.q) - q, axis=1)))

    def add(self, q: np.ndarray, parent: int) -> int:
        self.q.append(q)
        self.parent.append(parent)
        return len(self.q) - 1

    def branch(self, i: int) -> list[np.ndarray]:
        """Configurations from node ``i`` back to its root."""
        out = []
        while i >= 0:
            out.append(self.q[i])
            i = self.parent[i]
        return out


def rrt_connect(checker: ConfigurationChecker, start: np.ndarray, goals: np.ndarray, rng: np.random.Generator,
                approaches: Sequence[tuple[np.ndarray, int]] = (), step: float = 0.3, resolution: float = RESOLUTION,
                max_nodes: int = 500) -> np.ndarray | None:
    """A collision-free path (k, n_joints) from ``start`` to one of ``goals`` (m, n_joints), or None within
    ``max_nodes``.

    ``approaches`` are (configuration, goal index) pairs already joined to their goal by a free straight edge
    (the arm backed out of a shelf, or lifted above the clutter): the goal tree starts with them, so the search
    only has to reach the open space in front of a narrow passage. The straight lines to every node of that
    tree are tried first. Then the start tree and the goal tree take turns: one extends towards a random sample
    (or, one time in five, a goal), the other then grows straight at the new node until it connects or is
    blocked.
    """
    goal_tree = _Tree(goals)
    for q, parent in approaches:
        goal_tree.add(q, parent)
    start_tree = _Tree(start[None])
    trees = [start_tree, goal_tree]
    for i, q in enumerate(goal_tree.q):  # straight lines first: most layouts need nothing more
        if _edge_free(checker, start, q, resolution):
            return np.array([start, *goal_tree.branch(i)])
    while sum(len(t.q) for t in trees) < max_nodes:
        grow, other = trees
        sample = goals[rng.integers(len(goals))] if grow is start_tree and rng.uniform() < 0.2 else \
            rng.uniform(checker.lower, checker.upper)
        near = grow.nearest(sample)
        new = _steer(grow.q[near], sample, step)
        if _edge_free(checker, grow.q[near], new, resolution):
            added = grow.add(new, near)
            j = other.nearest(new)
            while True:  # connect: the other tree grows straight at the new node
                nxt = _steer(other.q[j], new, step)
                if not _edge_free(checker, other.q[j], nxt, resolution):
                    break
                j = other.add(nxt, j)
                if np.array_equal(nxt, new):
                    a, b = grow.branch(added), other.branch(j)
                    path = a[::-1] + b[1:] if grow is start_tree else b[::-1] + a[1:]
                    return np.array(path)
        trees.reverse()
    return None


def shortcut(checker: ConfigurationChecker, path: np.ndarray, rng: np.random.Generator, tries: int = 20,
             resolution: float = RESOLUTION) -> np.ndarray:
    """Random shortcutting: join two random path points straight where that edge is free."""
    path = list(path)
    for _ in range(tries):
        if len(path) < 3:
            break
        i, j = sorted(rng.choice(len(path), size=2, replace=False))
        if j - i > 1 and _edge_free(checker, path[i], path[j], resolution):
            path = path[: i + 1] + path[j:]
    return np.array(path)


class ArmPlanner:
    """Plans collision-free joint-space paths for an arm on one layout at a time.

    Args:
        margin: planning clearance, metres.
        fidelity: the collision fidelity the planner checks at.
        arm: the arm (the Panda by default).
    """

    def __init__(self, margin: float = 0.02, fidelity: str = "convex", arm: ArmModel | None = None) -> None:
        self.checker = ConfigurationChecker(fidelity, margin, arm)
        self.n_joints = self.checker.n_joints

    def plan(self, obstacles: Sequence[Obstacle], start: np.ndarray, target: np.ndarray,
             rng: np.random.Generator) -> np.ndarray | None:
        """A shortcut path (k, n_joints) from ``start`` to a clear configuration whose end effector is within
        ``GOAL_BALL`` of ``target`` on the layout ``obstacles`` (the table is always there), or None; every random
        choice is drawn from ``rng``."""
        self.checker.set_obstacles(obstacles)
        for _ in range(ATTEMPTS):
            goals = self.goals(start, target, rng)
            if not len(goals):
                continue
            for goal in goals:  # most layouts need no search: try the straight lines before the approaches
                if _edge_free(self.checker, start, goal, RESOLUTION):
                    return np.array([start, goal])
            path = rrt_connect(self.checker, start, goals, rng, self.approaches(goals, target))
            if path is not None:
                return shortcut(self.checker, path, rng)
        return None

    def approaches(self, goals: np.ndarray, target: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Per goal, configurations with the end effector ``APPROACH`` metres back towards the base (out of a
        shelf) and above (out of the clutter), where IK from the goal converges and the straight edge is free."""
        radial = approach_axis(target)
        ee = self.checker.ee_positions(goals)
        out = []
        for direction in (-radial, np.array([0.0, 0.0, 1.0])):
            aim = ee + APPROACH * direction  # one batched IK per direction, each seeded at its goal
            q = goals
            for _ in range(30):
                q = _dls_step(self.checker, q, aim)
            reached = np.linalg.norm(self.checker.ee_positions(q) - aim, axis=1) <= 0.005
            out.extend((q[i], i) for i in np.flatnonzero(reached)
                       if _edge_free(self.checker, q[i], goals[i], RESOLUTION))
        return out

    def goals(self, start: np.ndarray, target: np.ndarray, rng: np.random.Generator, rounds: int = 4,
              per_round: int = 64, enough: int = 4) -> np.ndarray:
        """Up to ``enough`` clear IK solutions, drawn in rounds of random seeds (the first round partly around
        ``start``) towards random points of the ball around ``target``; each round's solutions are checked nearest
        ``start`` first, a few at a time, until there are enough."""
        found: list[np.ndarray] = []
        for r in range(rounds):
            n = self.n_joints
            seeds = rng.uniform(self.checker.lower, self.checker.upper, (per_round, n))
            if r == 0:
                seeds[: per_round // 4] = start + rng.normal(0.0, 0.3, (per_round // 4, n))
            offsets = rng.normal(size=(per_round, 3))
            offsets *= GOAL_BALL * rng.uniform(size=(per_round, 1)) ** (1 / 3) / np.linalg.norm(
                offsets, axis=1, keepdims=True)
            # most targets converge within 20 iterations; the later rounds give awkward ones (low, deep in a
            # shelf) the 60 they may need
            q = inverse_kinematics(self.checker, target + offsets, seeds, iterations=20 if r < rounds // 2 else 60)
            q = q[np.argsort(np.linalg.norm(q - start, axis=1))]
            for chunk in np.array_split(q, np.arange(8, len(q), 8)):
                found.extend(chunk[self.checker.free(chunk, stop_at_first=False)])
                if len(found) >= enough:
                    return np.array(found[:enough])
        return np.array(found).reshape(-1, self.n_joints)


def time_parameterise(path: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Reference configurations one control step apart, each joint at most ``speed`` per step."""
    out = [path[0]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(b - a) / speed))))
        out.extend(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.array(out)

