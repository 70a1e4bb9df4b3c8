"""A student's memory of what its 2D LIDAR has seen, kept by dead reckoning: the robot's own map.

Every LIDAR return of the episode is kept as a point in the frame the episode started in, placed by integrating
the ``velocity`` entry (forward speed and yaw rate, as wheel odometry gives them) over the control period; points
5 cm apart or less count once. The policy is given the kept points around it in its own frame, as ``memory``:

* ``"polar"``: per LIDAR beam direction, the nearest kept point within ``reach`` metres, over ``reach`` (1 where
  none): a scan of everything seen so far, which still shows an obstacle the LIDAR no longer sees (out of range,
  hidden behind another, or passed);
* ``"grid"``: a ``cells`` x ``cells`` occupancy grid of ``cell`` metres, robot-centred and turned with it (row:
  ahead, column: left), flattened.

It reads only the observation (``lidar`` and ``velocity``), so a loaded agent keeps the same memory from the
observations it is given (:class:`~clutter_gym.training.agent.Agent`), and sensor noise reaches it as it reaches
the policy. Why a memory, and which: docs/learning.md ("How much of the teacher a student can see").
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

MEMORY_KINDS = ("polar", "grid")
#: the observation entry the memory is given as
MEMORY_KEY = "memory"
#: metres: returns closer than this to a kept one add nothing
VOXEL = 0.05


class ScanMemory:
    """The kept returns of one episode (see the module docstring).

    Args:
        kind: one of :data:`MEMORY_KINDS`.
        angles: the LIDAR's beam azimuths, radians.
        max_range: the LIDAR's range, metres (a reading of 1 is no return).
        dt: the control period, seconds (the odometry's integration step).
        reach: metres the polar memory looks.
        cells, cell: the grid's size in cells and a cell's edge in metres.
    """

    def __init__(self, kind: str, angles: np.ndarray, max_range: float, dt: float, reach: float = 6.0,
                 cells: int = 32, cell: float = 0.2) -> None:
        if kind not in MEMORY_KINDS:
            raise ValueError(f"scan_memory must be one of {MEMORY_KINDS} (or empty: none), got {kind!r}")
        self.kind, self.angles, self.max_range, self.dt = kind, np.asarray(angles, dtype=float), max_range, dt
        self.reach, self.cells, self.cell = reach, cells, cell
        self.size = len(self.angles) if kind == "polar" else cells * cells
        self.reset()

    def reset(self) -> None:
        self.x = self.y = self.yaw = 0.0
        self.points = np.zeros((0, 2))
        self._keys: set[tuple[int, int]] = set()

    def update(self, lidar: np.ndarray, velocity: np.ndarray | None) -> np.ndarray:
        """Move by ``velocity`` (None at an episode's first observation), keep ``lidar``'s returns, and return the
        memory entry."""
        if velocity is not None:
            self.yaw += float(velocity[1]) * self.dt
            step = float(velocity[0]) * self.dt
            self.x += step * math.cos(self.yaw)
            self.y += step * math.sin(self.yaw)
        ranges = np.asarray(lidar, dtype=float).reshape(-1) * self.max_range
        hit = ranges < self.max_range * (1.0 - 1e-6)
        if hit.any():
            angle = self.angles[hit] + self.yaw
            points = np.stack([self.x + ranges[hit] * np.cos(angle), self.y + ranges[hit] * np.sin(angle)], axis=1)
            keys = np.floor(points / VOXEL).astype(np.int64)
            new = [i for i, key in enumerate(map(tuple, keys)) if key not in self._keys]
            if new:
                self._keys.update(tuple(keys[i]) for i in new)
                self.points = np.concatenate([self.points, points[new]])
        return self.read()

    def read(self) -> np.ndarray:
        offset = self.points - (self.x, self.y)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        ahead, left = c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1]
        if self.kind == "polar":
            out = np.ones(len(self.angles), dtype=np.float32)
            distance = np.hypot(ahead, left)
            near = distance < self.reach
            if near.any():
                step = 2 * math.pi / len(self.angles)
                beam = np.round((np.arctan2(left[near], ahead[near]) - self.angles[0]) / step).astype(int)
                np.minimum.at(out, beam % len(self.angles), (distance[near] / self.reach).astype(np.float32))
            return out
        grid = np.zeros((self.cells, self.cells), dtype=np.float32)
        half = 0.5 * self.cells * self.cell
        i = np.floor((half - ahead) / self.cell).astype(int)  # row 0: farthest ahead
        j = np.floor((half - left) / self.cell).astype(int)  # column 0: farthest left
        inside = (i >= 0) & (i < self.cells) & (j >= 0) & (j < self.cells)
        grid[i[inside], j[inside]] = 1.0
        return grid.reshape(-1)


def memory_for(env: gym.Env, kind: str) -> ScanMemory:
    """A :class:`ScanMemory` for the 2D LIDAR of ``env`` (a ClutterNav env made with it).

    Raises:
        ValueError: the env has no 2D LIDAR or no velocity entry.
    """
    base = env.unwrapped
    lidar = next((s for s in getattr(base, "sensors", ()) if s.name == "lidar"), None)
    if lidar is None or lidar.config.n_channels != 1 or "velocity" not in env.observation_space.spaces:
        raise ValueError("scan_memory needs a ClutterNav env with a 2D LIDAR ('lidar' in sensors, lidar_channels 1)")
    return ScanMemory(kind, lidar.config.angles, lidar.config.max_range, 1.0 / base.metadata["render_fps"])


class MemoryObservation(gym.Wrapper):
    """Adds the ``memory`` entry (:class:`ScanMemory`) to the wrapped env's observations."""

    def __init__(self, env: gym.Env, kind: str) -> None:
        super().__init__(env)
        self.memory = memory_for(env, kind)
        self.observation_space = gym.spaces.Dict({**env.observation_space.spaces, MEMORY_KEY: gym.spaces.Box(
            0.0, 1.0, (self.memory.size,), np.float32)})

    def reset(self, **kwargs: Any) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.memory.reset()
        return {**obs, MEMORY_KEY: self.memory.update(obs["lidar"], None)}, info

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        memory = self.memory.update(obs["lidar"], obs["velocity"])
        return {**obs, MEMORY_KEY: memory}, reward, terminated, truncated, info
