"""A joint-space motion planner for the Panda on a known ClutterReach layout: the map-based reference.

It answers "how often does the layout allow a clean reach at all?", an upper bound for a policy that acts from the
same map. The parts are the textbook ones: goal configurations from position-only inverse kinematics (damped
least squares on the numpy forward kinematics, from random seeds), RRT-Connect (Kuffner and LaValle, 2000)
between the start and those goals, random shortcutting, and a path tracker that turns the path into the env's
joint-velocity actions. Every configuration is checked with the shapes the env checks contacts with (FCL, the
``convex`` level by default): each moving link at least ``margin`` from every obstacle and the table, and no
self-collision among the pairs the allowed-collision matrix enables; edges are checked every ``RESOLUTION``
radians of the joint that moves most.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import gymnasium as gym
import numpy as np

from clutter_gym.collision import CollisionChecker, RobotCollisionModel
from clutter_gym.collision.kinematics import UrdfKinematics
from clutter_gym.robots.panda import EE_LINK, FINGER_OPENING, LOWER, TRACKED_LINKS, UPPER, PandaArm
from clutter_gym.worlds.scene import Obstacle
from clutter_gym.worlds.tabletop import TABLE

#: Goal configurations put the end effector anywhere in this ball around the target (metres): well inside the
#: env's success radius, and far more IK solutions clear the clutter than at the exact point.
GOAL_BALL = 0.03
#: How far the approach configurations back the end effector away from a goal, metres.
APPROACH = 0.15
#: Largest joint change between two checked configurations of an edge, radians.
RESOLUTION = 0.03


class ConfigurationChecker:
    """Is a batch of arm configurations clear of a layout? One FK pass per batch, FCL per configuration.

    Args:
        fidelity: the collision fidelity of the robot's shapes (a ``collision_fidelity`` level).
        margin: least distance from every moving link to every obstacle, metres.
    """

    def __init__(self, fidelity: str = "convex", margin: float = 0.02) -> None:
        arm = PandaArm()
        self.kinematics = UrdfKinematics(arm.urdf_path)
        names = (arm.base_link, *TRACKED_LINKS)
        self.model = RobotCollisionModel.from_urdf(arm.urdf_path, fidelity, names)
        self.checker = CollisionChecker(self.model, base_link=arm.base_link, clearance_range=margin,
                                        fixed_links=(arm.base_link,))
        self._names = names
        self.margin = margin
        self.checks = 0  # configurations checked since construction (the planner's work)

    def set_obstacles(self, obstacles: Sequence[Obstacle]) -> None:
        """The layout to check against (the table is always added)."""
        self.checker.set_scene((*obstacles, TABLE), [])

    def frames(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Link frames (n, 4, 4) of arm configurations ``q`` (n, 7), fingers half open."""
        q = np.atleast_2d(q)
        fingers = np.full((len(q), 2), FINGER_OPENING)
        return self.kinematics.forward(np.concatenate([q, fingers], axis=1))

    def ee_positions(self, q: np.ndarray) -> np.ndarray:
        """End-effector positions (n, 3) of configurations ``q`` (n, 7)."""
        return self.frames(q)[EE_LINK][:, :3, 3]

    def clearance(self, q: np.ndarray) -> float:
        """Least distance (metres, negative in penetration, capped at ``margin``) from the moving links of one
        configuration ``q`` (7,) to the layout."""
        f = self._stacked_frames(np.asarray(q)[None])[0]
        return self._clearance(f)

    def free(self, q: np.ndarray, stop_at_first: bool = True) -> np.ndarray:
        """Per configuration of ``q`` (n, 7): clear of the layout by ``margin`` and free of self-collision.

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
                       iterations: int = 60, damping: float = 0.05, tolerance: float = 0.005) -> np.ndarray:
    """Position-only IK from every seed (n, 7) at once towards ``target`` (3,) or one target per seed (n, 3);
    returns the configurations that converged within ``tolerance`` (m, 7).

    Damped least squares on a finite-difference Jacobian of the end-effector position, clamped to the joint
    limits after every update; the orientation is free (success in ClutterReach is a position).
    """
    q = np.clip(np.asarray(seeds, dtype=float), LOWER, UPPER)
    for _ in range(iterations):
        q = _dls_step(checker, q, target, damping)
    error = np.linalg.norm(checker.ee_positions(q) - target, axis=-1)
    return q[error <= tolerance]


def _dls_step(checker: ConfigurationChecker, q: np.ndarray, target: np.ndarray, damping: float = 0.05) -> np.ndarray:
    """One damped-least-squares update of configurations ``q`` (n, 7) towards end-effector ``target``."""
    n, eps = len(q), 1e-5
    probes = np.concatenate([q[:, None, :], q[:, None, :] + eps * np.eye(7)[None]], axis=1)  # (n, 8, 7)
    p = checker.ee_positions(probes.reshape(-1, 7)).reshape(n, 8, 3)
    error = target - p[:, 0]
    jac = (p[:, 1:] - p[:, :1]).transpose(0, 2, 1) / eps  # (n, 3, 7)
    jjt = jac @ jac.transpose(0, 2, 1) + damping**2 * np.eye(3)
    step = (jac.transpose(0, 2, 1) @ np.linalg.solve(jjt, error[..., None]))[..., 0]
    return np.clip(q + np.clip(step, -0.3, 0.3), LOWER, UPPER)


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
                max_nodes: int = 1500) -> np.ndarray | None:
    """A collision-free path (k, 7) from ``start`` to one of ``goals`` (m, 7), or None within ``max_nodes``.

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
            rng.uniform(LOWER, UPPER)
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


def shortcut(checker: ConfigurationChecker, path: np.ndarray, rng: np.random.Generator, tries: int = 40,
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


class JointPlannerReacher:
    """The map-based reference for ClutterReach (``control="joint_velocity"``): plan on the known layout at
    every reset, then track the path.

    The tracker time-parameterises the path at the env's joint speed limits and commands, each step, the
    velocity that brings the measured joints to the next reference point. Without a plan (no IK solution clear
    of the layout, or RRT-Connect out of nodes) the arm holds still: the episode times out.

    Args:
        env: a ClutterReach env (its scene and joint speeds are read from it at every reset).
        margin: planning clearance, metres.
        fidelity: the collision fidelity the planner checks at.
        seed: the planner's random stream (goal seeds, samples, shortcuts).

    Raises:
        ValueError: the env is not under joint-velocity control.
    """

    def __init__(self, env: gym.Env, margin: float = 0.02, fidelity: str = "convex", seed: int = 0) -> None:
        base = env.unwrapped
        config = getattr(base.robot, "config", None)
        if getattr(config, "control", None) != "joint_velocity":
            raise ValueError("JointPlannerReacher needs a ClutterReach env made with control='joint_velocity'")
        self.env = base
        self.checker = ConfigurationChecker(fidelity, margin)
        self.rng = np.random.default_rng(seed)
        self.speed = base.robot.speed * base.robot.control_dt  # rad per step at an action of 1
        self._scene = None
        self.reference: np.ndarray | None = None
        self._k = 0
        self.planned = self.failed = 0

    def plan(self, start: np.ndarray, target: np.ndarray) -> np.ndarray | None:
        """A shortcut path (k, 7) from ``start`` to a clear configuration whose end effector is within
        ``GOAL_BALL`` of ``target``, or None."""
        goals = self.goals(start, target)
        if not len(goals):
            return None
        path = rrt_connect(self.checker, start, goals, self.rng, self.approaches(goals, target))
        return None if path is None else shortcut(self.checker, path, self.rng)

    def approaches(self, goals: np.ndarray, target: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Per goal, configurations with the end effector ``APPROACH`` metres back towards the base (out of a
        shelf) and above (out of the clutter), where IK from the goal converges and the straight edge is free."""
        radial = np.array([target[0], target[1], 0.0]) / max(np.hypot(target[0], target[1]), 1e-9)
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

    def goals(self, start: np.ndarray, target: np.ndarray, rounds: int = 4, per_round: int = 64,
              enough: int = 4) -> np.ndarray:
        """Up to ``enough`` clear IK solutions nearest ``start``, drawn in rounds of random seeds (the first
        round partly around ``start``) towards random points of the ball around ``target``."""
        found = []
        for r in range(rounds):
            seeds = self.rng.uniform(LOWER, UPPER, (per_round, 7))
            if r == 0:
                seeds[: per_round // 4] = start + self.rng.normal(0.0, 0.3, (per_round // 4, 7))
            offsets = self.rng.normal(size=(per_round, 3))
            offsets *= GOAL_BALL * self.rng.uniform(size=(per_round, 1)) ** (1 / 3) / np.linalg.norm(
                offsets, axis=1, keepdims=True)
            q = inverse_kinematics(self.checker, target + offsets, seeds)
            found.extend(q[self.checker.free(q, stop_at_first=False)] if len(q) else [])
            if len(found) >= enough:
                break
        goals = np.array(found).reshape(-1, 7)
        return goals[np.argsort(np.linalg.norm(goals - start, axis=1))][:enough]

    def _new_episode(self) -> None:
        scene = self.env.scene
        self.checker.set_obstacles(scene.obstacles)
        start, target = np.array(scene.start), np.array(scene.target)
        path = self.plan(start, target)
        self.planned += path is not None
        self.failed += path is None
        self.reference = None if path is None else _time_parameterise(path, self.speed)
        self._scene, self._k = scene, 0

    def __call__(self, obs: Mapping[str, np.ndarray]) -> np.ndarray:
        if self.env.scene is not self._scene:
            self._new_episode()
        if self.reference is None:
            return np.zeros(7, dtype=np.float32)
        self._k = min(self._k + 1, len(self.reference) - 1)
        q = np.asarray(obs["joint_position"], dtype=float)
        return np.clip((self.reference[self._k] - q) / self.speed, -1.0, 1.0).astype(np.float32)


def _time_parameterise(path: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Reference configurations one control step apart, each joint at most ``speed`` per step."""
    out = [path[0]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(b - a) / speed))))
        out.extend(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.array(out)
