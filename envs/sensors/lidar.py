"""2D scanning LIDAR: one ``rayTestBatch`` per scan in the mount link's xy plane."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from clutter_gym.robots.state import RobotState
from clutter_gym.sim import Sim


@dataclass(frozen=True)
class LidarConfig:
    """Scan geometry. Range defaults are the TurtleBot3 LDS-01's (0.12-3.5 m; shared/sensor-noise-reference.md L8).

    Attributes:
        n_rays: beams per scan, in [1, 4096].
        fov: field of view in radians, in (0, 2 pi]; beams are spread evenly, centred on the mount's +x axis
            (a full circle does not repeat its first beam).
        max_range: metres, in (min_range, 100]; a beam with no return reads ``max_range``.
        min_range: metres, in [0, 1); beams start this far from the mount so they never hit the robot itself.
        mount_height: offset of the scan plane above the mount link origin along its z axis, metres, [-0.5, 2].
        link: URDF link the LIDAR is mounted on.
    """

    n_rays: int = 64
    fov: float = 2 * math.pi
    max_range: float = 3.5
    min_range: float = 0.12
    mount_height: float = 0.0
    link: str = "lidar_link"

    def __post_init__(self) -> None:
        if isinstance(self.n_rays, bool) or not isinstance(self.n_rays, (int, np.integer)) or not 1 <= self.n_rays <= 4096:
            raise ValueError(f"n_rays must be an integer in [1, 4096], got {self.n_rays!r}")
        if not (math.isfinite(self.fov) and 0 < self.fov <= 2 * math.pi + 1e-9):
            raise ValueError(f"lidar_fov must be in (0, 2*pi] radians, got {self.fov!r}")
        if not (math.isfinite(self.min_range) and 0.0 <= self.min_range < 1.0):
            raise ValueError(f"lidar_min_range must be in [0, 1) metres, got {self.min_range!r}")
        if not (math.isfinite(self.max_range) and self.min_range < self.max_range <= 100.0):
            raise ValueError(f"lidar_range must be in ({self.min_range}, 100] metres, got {self.max_range!r}")
        if not (math.isfinite(self.mount_height) and -0.5 <= self.mount_height <= 2.0):
            raise ValueError(f"lidar_mount_height must be in [-0.5, 2] metres, got {self.mount_height!r}")

    @property
    def angles(self) -> np.ndarray:
        """Beam angles in the mount frame, radians, counter-clockwise from +x."""
        if self.fov >= 2 * math.pi - 1e-9:  # full circle: the last beam must not repeat the first
            return -math.pi + 2 * math.pi * np.arange(self.n_rays) / self.n_rays
        if self.n_rays == 1:
            return np.zeros(1)
        return np.linspace(-self.fov / 2, self.fov / 2, self.n_rays)


class Lidar:
    """Ranges in metres (``info["lidar_ranges"]``); observation = ranges / max_range in [0, 1]."""

    name = "lidar"
    info_key = "lidar_ranges"

    def __init__(self, config: LidarConfig | None = None) -> None:
        self.config = c = config or LidarConfig()
        self.observation_space = spaces.Box(0.0, 1.0, shape=(c.n_rays,), dtype=np.float32)
        a = c.angles
        dirs = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
        centre = np.array([0.0, 0.0, c.mount_height])
        # beams in the mount link's frame: constant, pybullet moves them with the link
        self.ray_starts = (centre + c.min_range * dirs).tolist()
        self.ray_ends = (centre + c.max_range * dirs).tolist()
        self._span = c.max_range - c.min_range

    def reset(self, state: RobotState) -> None:
        """A LIDAR keeps no state between scans."""

    def read(self, sim: Sim, state: RobotState) -> np.ndarray:
        """Ranges (metres) measured from the mount origin, ``max_range`` where nothing is hit."""
        link = state.link_index[self.config.link]
        fractions = sim.ray_hit_fractions(self.ray_starts, self.ray_ends, body=state.body, link=link)
        return self.config.min_range + fractions * self._span

    def observe(self, reading: np.ndarray) -> np.ndarray:
        return (reading / self.config.max_range).astype(np.float32)
