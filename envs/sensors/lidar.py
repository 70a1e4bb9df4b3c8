"""2D or multi-channel scanning LIDAR: one batched ray cast per scan (the exact caster, or ``rayTestBatch``), cast from
the mount link's frame."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.noise.lidar import LidarEpisode, LidarNoise, angle_offsets, apply_lidar_noise, start_lidar_episode
from clutter_gym.sensors.suite import Observed
from clutter_gym.sim import RAY_CASTERS, Sim
from clutter_gym.util.checks import check_integer


@dataclass(frozen=True)
class LidarConfig:
    """Scan geometry. Range defaults are the TurtleBot3 LDS-01's (0.12-3.5 m; docs/sensor-noise-reference.md L8),
    the sensor window of the ``harsh`` noise profile too (profiles.yaml, held equal by
    tests/noise/test_noise_profiles.py); ClutterNav's ``lidar_range`` default is ``max_range``.

    Attributes:
        n_rays: beams per channel, in [1, 4096].
        fov: horizontal field of view in radians, in (0, 2 pi]; beams are spread evenly, centred on the mount's +x
            axis (a full circle does not repeat its first beam).
        max_range: metres, in (min_range, 100]; a beam with no return reads ``max_range``.
        min_range: metres, in [0, 1); beams start this far from the mount so they never hit the robot itself.
        mount_height: offset of the scan origin above the mount link origin along its z axis, metres, [-0.5, 2].
        n_channels: vertical channels (1 = a 2D scanner), in [1, 128].
        vertical_fov: spread of the channels' elevation angles in radians, [0, pi/2]; channels are evenly spaced
            and centred on the horizontal plane (a VLP-16 is 16 channels over 30 degrees).
        link: URDF link the LIDAR is mounted on.
        caster: "exact" (the default: beams cast against the world's true boxes, cylinders and ground plane, in about
            a tenth of pybullet's time; pybullet casts them anyway in a world holding anything else a ray can hit)
            or "pybullet" (``rayTestBatch``, cylinders as 64-gon prisms). See :meth:`Sim.ray_hit_fractions`.
    """

    n_rays: int = 64
    fov: float = 2 * math.pi
    max_range: float = 3.5
    min_range: float = 0.12
    mount_height: float = 0.0
    n_channels: int = 1
    vertical_fov: float = 0.0
    link: str = "lidar_link"
    caster: str = "exact"

    def __post_init__(self) -> None:
        check_integer("n_rays", self.n_rays, 1, 4096)
        check_integer("lidar_channels", self.n_channels, 1, 128)
        if not (math.isfinite(self.fov) and 0 < self.fov <= 2 * math.pi + 1e-9):
            raise ValueError(f"lidar_fov must be in (0, 2*pi] radians, got {self.fov!r}")
        if not (math.isfinite(self.vertical_fov) and 0 <= self.vertical_fov <= math.pi / 2):
            raise ValueError(f"lidar_vertical_fov must be in [0, pi/2] radians, got {self.vertical_fov!r}")
        if not (math.isfinite(self.min_range) and 0.0 <= self.min_range < 1.0):
            raise ValueError(f"lidar_min_range must be in [0, 1) metres, got {self.min_range!r}")
        if not (math.isfinite(self.max_range) and self.min_range < self.max_range <= 100.0):
            raise ValueError(f"lidar_range must be in ({self.min_range}, 100] metres, got {self.max_range!r}")
        if not (math.isfinite(self.mount_height) and -0.5 <= self.mount_height <= 2.0):
            raise ValueError(f"lidar_mount_height must be in [-0.5, 2] metres, got {self.mount_height!r}")
        if self.caster not in RAY_CASTERS:
            raise ValueError(f"lidar_caster must be one of {RAY_CASTERS}, got {self.caster!r}")

    @property
    def angles(self) -> np.ndarray:
        """Beam azimuths in the mount frame, radians, counter-clockwise from +x."""
        if self.fov >= 2 * math.pi - 1e-9:  # full circle: the last beam must not repeat the first
            return -math.pi + 2 * math.pi * np.arange(self.n_rays) / self.n_rays
        if self.n_rays == 1:
            return np.zeros(1)
        return np.linspace(-self.fov / 2, self.fov / 2, self.n_rays)

    @property
    def elevations(self) -> np.ndarray:
        """Channel elevation angles, radians, bottom channel first."""
        if self.n_channels == 1:
            return np.zeros(1)
        return np.linspace(-self.vertical_fov / 2, self.vertical_fov / 2, self.n_channels)

    @property
    def shape(self) -> tuple[int, ...]:
        """(n_rays,) for a 2D scanner, (n_channels, n_rays) otherwise."""
        return (self.n_rays,) if self.n_channels == 1 else (self.n_channels, self.n_rays)


class Lidar:
    """Ranges in metres (``info["lidar_ranges"]``); observation ``lidar`` = ranges / max_range in [0, 1].

    Noise (:mod:`clutter_gym.noise.lidar`) is applied to the physical ranges; a no-return reads ``max_range`` in
    the observation whichever convention ``info`` uses.
    """

    name = "lidar"
    read_every_step = False
    renders = False
    observation = (Observed(
        "lidar", "(`n_rays`,), or (`n_channels`, `n_rays`) with more than one channel",
        "range / `max_range`, beams spread over `fov` counter-clockwise and centred on its link's +x, channels bottom "
        "up; a beam without a return reads 1", "-; its link", "[0, 1]"),)

    def __init__(self, config: LidarConfig | None = None, noise: LidarNoise | None = None) -> None:
        self.config = c = config or LidarConfig()
        self.noise = noise or LidarNoise()
        lo, hi = max(c.min_range, self.noise.min_range), min(c.max_range, self.noise.max_range)
        if lo >= hi:  # every reading would be a no-return
            raise ValueError(f"the LIDAR's range window is empty: it reads from max(lidar min {c.min_range}, "
                             f"lidar.min_range {self.noise.min_range}) = {lo} m to min(lidar_range {c.max_range}, "
                             f"lidar.max_range {self.noise.max_range}) = {hi} m")
        self.spaces = {"lidar": spaces.Box(0.0, 1.0, shape=c.shape, dtype=np.float32)}
        self.needs_bodies = c.caster == "pybullet"  # the exact caster casts against the Sim's primitives
        az = np.broadcast_to(c.angles, c.shape).reshape(-1)
        el = np.repeat(c.elevations, c.n_rays)
        self._dirs = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)
        self._d_dirs = np.stack([-np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), 0 * el], axis=1)  # d/d azimuth
        self._centre = np.array([0.0, 0.0, c.mount_height])
        self._starts = self._centre + c.min_range * self._dirs  # mount frame
        self._ends = self._centre + c.max_range * self._dirs
        # as lists too, for pybullet to move with a mount link of its own (it converts lists faster than arrays)
        self.ray_starts, self.ray_ends = self._starts.tolist(), self._ends.tolist()
        self._span = c.max_range - c.min_range
        self._episode = LidarEpisode()

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        self._episode = start_lidar_episode(rng, self.noise)

    def read_clean(self, sim: Sim, state: RobotState, starts: np.ndarray | None = None, ends: np.ndarray | None = None):
        """Exact ranges (metres) from the mount origin, ``max_range`` where nothing is hit; the beams given by
        ``starts`` and ``ends`` (mount frame) or the scan's own.

        A mount among the state's tracked links is placed where the state has it (a link of a rigid body merged
        into one pybullet body has no pybullet frame); any other is pybullet's link, which moves the rays itself.
        """
        if self.config.link in state.link_names:
            row = state.link(self.config.link)
            origin, axes = state.links.position[row], state.links.rotation[row]
            starts, ends = (self._starts, self._ends) if starts is None or ends is None else (starts, ends)
            if self.config.caster == "exact" and sim.rays.exact_rays_model_world():
                fractions = sim.rays.cast_exact(starts, ends, origin, axes)
            else:
                fractions = sim.rays.ray_hit_fractions(starts @ axes.T + origin, ends @ axes.T + origin)
        else:
            if starts is None or ends is None:  # pybullet converts ready lists faster, the exact caster takes arrays
                exact = self.config.caster == "exact"
                starts, ends = (self._starts, self._ends) if exact else (self.ray_starts, self.ray_ends)
            fractions = sim.rays.ray_hit_fractions(starts, ends, body=state.body,
                                                   link=state.link_index[self.config.link], caster=self.config.caster)
        return (self.config.min_range + fractions * self._span).reshape(self.config.shape)

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> np.ndarray:
        c = self.config
        offsets = angle_offsets((len(self._dirs), 1), rng, self.noise)
        if offsets is None:
            clean = self.read_clean(sim, state)
        else:
            # first order in the azimuth error d, half the cost of recomputing cos/sin: ranges come out short by
            # a factor 1 / sqrt(1 + d^2), 4e-5 for a 1-sigma error of 0.0087 rad (harsh; 0.13 mm at 3.5 m)
            dirs = self._dirs + offsets * self._d_dirs
            clean = self.read_clean(sim, state, self._centre + c.min_range * dirs, self._centre + c.max_range * dirs)
        return apply_lidar_noise(clean, rng, self.noise, self._episode, c.min_range, c.max_range)

    def observe(self, reading: np.ndarray) -> dict[str, np.ndarray]:
        return {"lidar": (np.minimum(reading, self.config.max_range) / self.config.max_range).astype(np.float32)}

    def info(self, reading: np.ndarray) -> dict[str, Any]:
        return {"lidar_ranges": reading}
