"""Camera on a robot link: RGB, depth and segmentation from one ``getCameraImage`` per frame, or depth and
segmentation ray cast against the world's exact boxes and cylinders.

The image is rendered only when the sensor is due (its rate, see the noise profile's ``camera.rate_hz``) and only
with the modes asked for. TinyRenderer's cost grows with the triangles of every visual shape in the world and
with the pixels, so the robots and clutter keep their visual meshes lean; the ray caster's with the pixels and the
shapes behind each (docs/benchmarks.md has both).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from clutter_gym.datatypes import RobotState
from clutter_gym.noise.camera import (
    DepthEpisode,
    DepthNoise,
    RgbEpisode,
    RgbNoise,
    apply_depth_noise,
    apply_rgb_noise,
    start_depth_episode,
    start_rgb_episode,
)
from clutter_gym.noise.distortion import Intrinsics
from clutter_gym.sensors.suite import Observed
from clutter_gym.sim import Sim
from clutter_gym.sim.primitives import BACKDROP_ID
from clutter_gym.util.transforms import quat_to_matrix, rpy_quat

CAMERA_MODES = ("rgb", "depth", "segmentation")
RENDERERS = ("tiny", "egl", "rays")
#: The modes the ray caster draws (it has no colours).
RAY_MODES = ("depth", "segmentation")
#: Segmentation classes, by value: what each pixel shows.
SEGMENTATION_CLASSES = ("nothing", "ground", "obstacle", "robot", "goal")
_OBSTACLE = SEGMENTATION_CLASSES.index("obstacle")


@dataclass(frozen=True)
class CameraConfig:
    """Attributes:
    width, height: image size in pixels, each in [8, 1024].
    modes: a non-empty subset of ("rgb", "depth", "segmentation").
    vertical_fov: radians, (0, pi); 58 degrees is the RealSense D435's depth field of view.
    near, far: clipping planes in metres; nothing closer than ``near`` or beyond ``far`` is seen, and depth
        pixels there read 0 (no data).
    renderer: "tiny" (TinyRenderer, CPU, always available), "egl" (OpenGL through the EGL plugin) or "rays" (depth
        and segmentation only, ray cast on the CPU against the exact boxes, cylinders, ground and markers of the
        world, see :meth:`clutter_gym.sim.Sim.ray_cast_image`; robots are not drawn, so it suits a camera that
        sees no part of its own robot).
    link: URDF link the camera is mounted on; it looks along the link's +x axis with +z up.
    mount_xyz, mount_rpy: the camera's frame in the link's (metres; roll, pitch, yaw in radians, URDF order): a
        camera placed and turned on a link whose axes do not point where it looks (a wrist camera on a hand).
    """

    width: int = 84
    height: int = 84
    modes: tuple[str, ...] = ("rgb", "depth")
    vertical_fov: float = math.radians(58.0)
    near: float = 0.05
    far: float = 10.0
    renderer: str = "tiny"
    link: str = "camera_link"
    mount_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name, value in (("camera_size[0] (width)", self.width), ("camera_size[1] (height)", self.height)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 8 <= value <= 1024:
                raise ValueError(f"{name} must be an integer in [8, 1024] pixels, got {value!r}")
        if isinstance(self.modes, str) or not self.modes or any(m not in CAMERA_MODES for m in self.modes):
            raise ValueError(f"camera_modes must be a non-empty tuple of names from {CAMERA_MODES}, got {self.modes!r}")
        if len(set(self.modes)) != len(self.modes):
            raise ValueError(f"camera_modes must not repeat a name, got {self.modes!r}")
        if not (math.isfinite(self.vertical_fov) and 0.0 < self.vertical_fov < math.pi):
            raise ValueError(f"camera_fov must be in (0, pi) radians, got {self.vertical_fov!r}")
        if not (math.isfinite(self.near) and math.isfinite(self.far) and 0.001 <= self.near < self.far <= 1000.0):
            raise ValueError(f"camera near/far must satisfy 0.001 <= near < far <= 1000 m, got {self.near}, {self.far}")
        if self.renderer not in RENDERERS:
            raise ValueError(f"camera_renderer must be one of {RENDERERS}, got {self.renderer!r}")
        if self.renderer == "rays" and not set(self.modes) <= set(RAY_MODES):
            raise ValueError(f"camera_renderer='rays' draws only {RAY_MODES}, but camera_modes is {self.modes!r}: "
                             "use camera_renderer='tiny' or 'egl' for rgb")

    @property
    def intrinsics(self) -> Intrinsics:
        """Pinhole intrinsics of the rendered image (pixel indices, row 0 at the top).

        TinyRenderer samples each pixel at its corner, not its centre, so its principal point is
        ``(width / 2, height / 2 - 1)``, half a pixel off the ``((width - 1) / 2, (height - 1) / 2)`` of a
        centre-sampling renderer, which EGL's OpenGL rasteriser is assumed to be
        (docs/design-notes.md#pixel-sampling). The ray caster casts through pixel centres.
        """
        ideal = Intrinsics.from_fov(self.width, self.height, self.vertical_fov)
        if self.renderer != "tiny":
            return ideal
        return Intrinsics(self.width, self.height, ideal.fx, ideal.fy, self.width / 2, self.height / 2 - 1)


def camera_config(size: Any, modes: Any, fov: float, far: float, renderer: str | None,
                  link: str = CameraConfig.link, mount_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0),
                  mount_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> CameraConfig:
    """The camera of an env's ``camera_size``, ``camera_modes``, ``camera_fov``, ``camera_far`` and
    ``camera_renderer`` keyword arguments, mounted on ``link``; errors name the argument. Renderer None: "rays"
    when the modes are ones it draws, else "tiny"."""
    if isinstance(size, (str, bytes)) or not isinstance(size, Sequence) or len(size) != 2:
        raise ValueError(f"camera_size must be (width, height) in pixels, got {size!r}")
    if isinstance(modes, str) or not isinstance(modes, Sequence):
        raise ValueError(f"camera_modes must be a tuple of names, got {modes!r}")
    if renderer is None:
        renderer = "rays" if modes and all(m in RAY_MODES for m in modes) else "tiny"
    return CameraConfig(width=size[0], height=size[1], modes=tuple(modes), vertical_fov=fov, far=far, renderer=renderer,
                        link=link, mount_xyz=mount_xyz, mount_rpy=mount_rpy)


class Camera:
    """Observation entries, one per mode:

    * ``camera_rgb``: (height, width, 3) uint8;
    * ``camera_depth``: (height, width) float32, metres along the optical axis, 0 = no data;
    * ``camera_segmentation``: (height, width) uint8, index into :data:`SEGMENTATION_CLASSES`.
    """

    name = "camera"
    read_every_step = False
    observation = (
        Observed("camera_rgb", "(h, w, 3) uint8, (w, h) = `size`", 'colour image (with "rgb" in `modes`)',
                 "-; looking along its link's +x, +z up", "[0, 255]"),
        Observed("camera_depth", "(h, w)", 'depth along the optical axis, 0 = no data (with "depth")', "m",
                 "[0, `far`]"),
        Observed("camera_segmentation", "(h, w) uint8",
                 'class per pixel: nothing, ground, obstacle, robot, goal (with "segmentation")', "-", "[0, 4]"),
    )

    def __init__(self, config: CameraConfig | None = None, rgb_noise: RgbNoise | None = None,
                 depth_noise: DepthNoise | None = None) -> None:
        self.config = c = config or CameraConfig()
        self.rgb_noise = rgb_noise or RgbNoise()
        self.depth_noise = depth_noise or DepthNoise()
        shape = (c.height, c.width)
        all_spaces: dict[str, spaces.Space] = {
            "rgb": spaces.Box(0, 255, (*shape, 3), dtype=np.uint8),
            "depth": spaces.Box(0.0, c.far, shape, dtype=np.float32),
            "segmentation": spaces.Box(0, len(SEGMENTATION_CLASSES) - 1, shape, dtype=np.uint8),
        }
        self.spaces = {f"camera_{mode}": all_spaces[mode] for mode in c.modes}
        self.intrinsics = c.intrinsics
        f = 1.0 / math.tan(c.vertical_fov / 2)
        aspect = c.width / c.height
        # OpenGL perspective projection, column-major (what pybullet's computeProjectionMatrixFOV returns)
        self.projection = [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (c.far + c.near) / (c.near - c.far), -1,
                           0, 0, 2 * c.far * c.near / (c.near - c.far), 0]
        self._rgb_episode, self._depth_episode = RgbEpisode(), DepthEpisode()
        self._classes = np.zeros(1, dtype=np.uint8)
        self._egl_loaded = False
        mounted = c.mount_xyz != (0.0, 0.0, 0.0) or c.mount_rpy != (0.0, 0.0, 0.0)
        self._mount = (np.array(c.mount_xyz, dtype=float), quat_to_matrix(rpy_quat(*c.mount_rpy))) if mounted else None
        self.renders = c.renderer != "rays"  # the ray caster needs no visual shapes in the world
        self.needs_bodies = self.renders  # and sees obstacles without bodies (Sim.ray_cast_image)

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        if self.config.renderer == "egl" and not self._egl_loaded:
            sim.rendering.use_egl()
            self._egl_loaded = True
        self._rgb_episode = start_rgb_episode(rng, self.rgb_noise)
        self._depth_episode = start_depth_episode(rng, self.depth_noise)
        if "segmentation" in self.config.modes:
            self._classes = _class_table(sim)

    def render(self, sim: Sim, state: RobotState) -> dict[str, np.ndarray]:
        """The clean images of the requested modes (depth in metres, 0 where nothing is within [near, far])."""
        c = self.config
        if c.link in state.link_names:  # where the state has it: a merged rigid body's links have no pybullet frame
            row = state.link(c.link)
            eye, rotation = state.links.position[row], state.links.rotation[row]
        else:
            eye, rotation = sim.link_frame(state.body, state.link_index[c.link])
        if self._mount is not None:
            eye, rotation = eye + rotation @ self._mount[0], rotation @ self._mount[1]
        images: dict[str, np.ndarray] = {}
        ids: np.ndarray | None  # None: no segmentation was asked of the rasteriser
        if c.renderer == "rays":
            i = self.intrinsics
            axes = np.array([rotation[:, 0], -rotation[:, 1], -rotation[:, 2]])  # forward, right, down
            images["depth"], ids = sim.rendering.ray_cast_image(c.width, c.height, eye, axes, (i.fx, i.fy, i.cx, i.cy),
                                                                c.near, c.far)
        else:
            view = _view_matrix(eye, rotation)
            images["rgb"], buffer, ids = sim.rendering.camera_image(
                c.width, c.height, view, self.projection, "segmentation" in c.modes, behind=state.body
            )
            if "depth" in c.modes:
                # the depth buffer is non-linear in z: invert the projection. TinyRenderer leaves the background a
                # hair short of the far plane (z = 0.99999 far), so the last millimetre counts as nothing seen.
                z = c.far * c.near / (c.far - (c.far - c.near) * buffer)
                images["depth"] = np.where(z < c.far - 1e-3, z, 0.0)
        if "segmentation" in c.modes:
            assert ids is not None
            table = self._classes
            # bodies made after the reset (a large scene's near obstacles) and obstacles without a body
            # (Sim.ray_cast_image's BACKDROP_ID) are obstacles
            other = (ids == BACKDROP_ID) | (ids + 1 >= len(table))
            images["segmentation"] = np.where(other, _OBSTACLE, table[np.clip(ids + 1, 0, len(table) - 1)])
        return {mode: images[mode] for mode in c.modes}

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> dict[str, np.ndarray]:
        images = self.render(sim, state)
        if "rgb" in images:
            images["rgb"] = apply_rgb_noise(images["rgb"], rng, self.rgb_noise, self._rgb_episode, self.intrinsics)
        if "depth" in images:
            images["depth"] = apply_depth_noise(
                images["depth"], rng, self.depth_noise, self._depth_episode, self.intrinsics
            )
        return images

    def observe(self, reading: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        out = {f"camera_{mode}": image for mode, image in reading.items()}
        if "camera_depth" in out:
            out["camera_depth"] = np.minimum(out["camera_depth"], self.config.far).astype(np.float32)
        return out

    def info(self, reading: Any) -> dict[str, Any]:
        return {}


def _view_matrix(eye: np.ndarray, rotation: np.ndarray) -> list[float]:
    """OpenGL view matrix (column-major) of a camera at ``eye`` looking along the rotation's x axis, z up."""
    forward, up = rotation[:, 0], rotation[:, 2]
    side = -rotation[:, 1]  # camera right = forward x up = x_link x z_link = -y_link
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = side, up, -forward
    m[:3, 3] = -m[:3, :3] @ eye
    return m.T.reshape(-1).tolist()


def _class_table(sim: Sim) -> np.ndarray:
    """Lookup from body id + 1 to segmentation class (index 0 = no body); unnamed bodies are obstacles."""
    names = sim.body_names()
    size = max([*names, *sim.body_ids()], default=0) + 2
    table = np.full(size, SEGMENTATION_CLASSES.index("obstacle"), dtype=np.uint8)
    table[0] = SEGMENTATION_CLASSES.index("nothing")
    classes = {"ground": "ground", "robot": "robot", "goal": "goal"}
    for body, name in names.items():
        table[body + 1] = SEGMENTATION_CLASSES.index(classes.get(name, "obstacle"))
    return table
