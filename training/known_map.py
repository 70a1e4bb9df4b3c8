"""Teachers that plan on only what the LIDAR has hit: how much of a privileged teacher a sensor-reading student
could match (docs/learning.md, "How much of the teacher a student can see").

The planner references plan over the whole layout, so their path can go round a wall that no sensor has seen. These
teachers plan the same way on a layout of only the obstacles a LIDAR return has landed on (within :data:`MATCH`):
all of the episode's returns (``keep=True``, ``"seen-map"``: a robot that maps what it sees, as a student with a
memory could) or the current scan's alone (``keep=False``, ``"in-range"``: a memoryless student's view). Walls,
floor and ceiling are known, as an arena's size is. An obstacle seen is known whole, so the measure is an upper
bound on what the returns alone tell. The plan is redone whenever the known set changes; measurement only, far too
slow to label training data at scale on ClutterFly-v1.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from clutter_gym.training.teachers import PlannerFlyer, PlannerNavigator

#: metres: a return this close to an obstacle is taken as that obstacle seen
MATCH = 0.05


def _lidar(env: gym.Env, channels: int | None) -> Any:
    lidar = next((s for s in getattr(env.unwrapped, "sensors", ()) if s.name == "lidar"), None)
    if lidar is None or (channels is not None and lidar.config.n_channels != channels):
        need = "a 2D LIDAR ('lidar' in sensors, lidar_channels 1)" if channels == 1 else "a LIDAR ('lidar' in sensors)"
        raise ValueError(f"a teacher on what the LIDAR has seen needs {need}")
    return lidar


class _Known:
    """The obstacles seen so far (or in the last scan) and whether the plan must be redone."""

    def __init__(self, keep: bool) -> None:
        self.keep = keep
        self.reset()

    def reset(self) -> None:
        self.seen: frozenset[int] = frozenset()
        self.planned: frozenset[int] | None = None

    def update(self, gaps: np.ndarray) -> bool:
        """Add the obstacles of a scan, ``gaps`` (returns x obstacles, metres); True when the plan must be redone."""
        now: frozenset[int] = frozenset()
        if gaps.size:
            nearest = gaps.argmin(axis=1)
            now = frozenset(int(i) for i in nearest[gaps[np.arange(len(gaps)), nearest] < MATCH])
        self.seen = self.seen | now if self.keep else now
        if self.seen == self.planned:
            return False
        self.planned = self.seen
        return True


class _OnWhatIsKnown:
    """What the seen-map teachers share: the env, the planner's lookahead, the obstacles known so far and the
    path planned on them (replanned when they change)."""

    def _know(self, env: gym.Env, keep: bool) -> None:
        self.env: Any = env.unwrapped
        self.lookahead = float(self.env.task.subgoal_lookahead)
        self.known = _Known(keep)
        self._path: Any = None

    def reset(self) -> None:
        self.known.reset()

    def _replan(self, gaps: np.ndarray) -> bool:
        """Takes this scan's ``gaps`` (points x obstacles); True when the path must be planned again."""
        return self.known.update(gaps) or self._path is None


class SeenMapNavigator(_OnWhatIsKnown, PlannerNavigator):
    """ClutterNav-v1's planner reference (committed, as its student's teacher) on the obstacles the LIDAR has hit."""

    def __init__(self, env: gym.Env, commit: float, keep: bool, waypoint: bool = False) -> None:
        super().__init__(env, commit, waypoint)
        self._know(env, keep)
        lidar = _lidar(env, 1)
        self.angles, self.max_range = np.asarray(lidar.config.angles), float(lidar.config.max_range)

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        from clutter_gym.tasks.navigate import SUBGOAL_PLAN_MARGIN, polar
        from clutter_gym.worlds.floor.path import PathDistance
        from clutter_gym.worlds.floor.scene import Scene

        env = self.env
        state = env.robot_state()
        x, y, yaw = float(state.position[0]), float(state.position[1]), state.yaw
        ranges = np.asarray(info["lidar_ranges"], dtype=float)
        hit = np.isfinite(ranges) & (ranges < self.max_range - 1e-3)
        angle = self.angles[hit] + yaw
        points = np.stack([x + ranges[hit] * np.cos(angle), y + ranges[hit] * np.sin(angle)], axis=1)
        obstacles = env.scene.obstacles
        gaps = (np.stack([np.maximum(o.distance(points[:, 0], points[:, 1]), 0.0) for o in obstacles], axis=1)
                if obstacles else np.zeros((0, 0)))
        if self._replan(gaps):
            scene = env.scene
            layout = Scene(tuple(obstacles[i] for i in sorted(self.known.seen)), scene.start, scene.goal)
            self._path = PathDistance(layout, env.task.spec, env.task.robot_radius, plan_margin=SUBGOAL_PLAN_MARGIN)
        point = self._path.waypoint(x, y, lookahead=self.lookahead)
        return self._answer({**obs, "subgoal": polar(point, x, y, yaw, self.lookahead)})


class SeenMapFlyer(_OnWhatIsKnown, PlannerFlyer):
    """ClutterFly-v1's planner reference on the obstacles its LIDAR has hit."""

    def __init__(self, env: gym.Env, keep: bool, waypoint: bool = False) -> None:
        super().__init__(env, waypoint)
        self._know(env, keep)
        lidar = _lidar(env, None)
        c = lidar.config
        azimuth = np.broadcast_to(c.angles, c.shape).reshape(-1)
        elevation = np.repeat(c.elevations, c.n_rays)
        self.directions = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                                    np.sin(elevation)], axis=1)
        self.link, self.max_range = c.link, float(c.max_range)

    def __call__(self, obs: dict[str, np.ndarray], info: dict[str, Any]) -> np.ndarray:
        from clutter_gym.worlds.volume.path import VolumePathDistance
        from clutter_gym.worlds.volume.scene import VolumeScene

        env = self.env
        state = env.robot_state()
        row = state.link(self.link)
        ranges = np.asarray(info["lidar_ranges"], dtype=float).reshape(-1)
        hit = np.isfinite(ranges) & (ranges < self.max_range - 1e-3)
        points = state.links.position[row] + (self.directions[hit] * ranges[hit, None]) @ state.links.rotation[row].T
        obstacles = env.scene.obstacles
        gaps = np.array([[o.distance3d(p) for o in obstacles] for p in points]).reshape(len(points), len(obstacles))
        if self._replan(gaps):
            scene = env.scene
            layout = VolumeScene(tuple(obstacles[i] for i in sorted(self.known.seen)), scene.start, scene.goal)
            self._path = VolumePathDistance(layout, env.task.spec, env.task.robot_radius)
        position = np.asarray(state.position)
        point = self._path.waypoint(*position.tolist(), lookahead=self.lookahead)
        offset = state.rotation.T @ (np.asarray(point) - position)
        subgoal = np.clip(offset, -self.lookahead, self.lookahead).astype(np.float32)
        return super().__call__({**obs, "subgoal": subgoal}, info)
