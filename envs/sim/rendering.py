"""Pictures of the world: the ``rgb_array`` render, robot-mounted camera images (rasterised, or ray cast for depth
and segmentation), the GUI camera, EGL.

A part of :class:`clutter_gym.sim.Sim` (``sim.rendering``) on the Sim's
:class:`~clutter_gym.sim.world_record.WorldRecord`: its client id, visual-colour cache, view culler and primitives.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence

import numpy as np
import pybullet as pb

from clutter_gym.sim.ray_casting import cast_depth
from clutter_gym.sim.world_record import WorldRecord
from clutter_gym.util.camera_view import FAR, FOV_DEG, NEAR, UP
from clutter_gym.util.quiet import quiet_c_output

_INVISIBLE = (0.0, 0.0, 0.0, 0.0)


class Rendering:
    """Camera images of a Sim's world, with TinyRenderer until :meth:`use_egl`."""

    def __init__(self, record: WorldRecord) -> None:
        self._record = record
        self._renderer = pb.ER_TINY_RENDERER

    def render(
        self,
        width: int,
        height: int,
        eye: Sequence[float],
        target: Sequence[float],
        fov_deg: float = FOV_DEG,
    ) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 from TinyRenderer looking from ``eye`` to ``target`` (world frame,
        metres, z up) with a vertical field of view of ``fov_deg`` degrees; :class:`clutter_gym.util.camera_view.
        CameraView` places world points in it.

        Raises:
            RuntimeError: this Sim has no visuals.
        """
        rgba, _ = self._look(width, height, eye, target, fov_deg, segmentation=False)
        return rgba[:, :, :3].copy()

    def render_segmentation(
        self, width: int, height: int, eye: Sequence[float], target: Sequence[float], fov_deg: float = FOV_DEG,
    ) -> np.ndarray:
        """The body id per pixel (height, width), -1 where there is none, of the picture :meth:`render` takes with
        the same arguments.

        Raises:
            RuntimeError: this Sim has no visuals.
        """
        _, seg = self._look(width, height, eye, target, fov_deg, segmentation=True)
        assert seg is not None  # asked for
        return np.where(seg >= 0, seg & ((1 << 24) - 1), -1)  # low 24 bits: the body id

    def _look(self, width: int, height: int, eye: Sequence[float], target: Sequence[float], fov_deg: float,
              segmentation: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """One TinyRenderer ``getCameraImage`` of a look-at camera: RGBA, and the raw segmentation if asked."""
        self._check_visuals()
        view = pb.computeViewMatrix(eye, target, UP, physicsClientId=self._record.cid)
        proj = pb.computeProjectionMatrixFOV(fov_deg, width / height, NEAR, FAR, physicsClientId=self._record.cid)
        flags = pb.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX if segmentation else pb.ER_NO_SEGMENTATION_MASK
        _, _, rgba, _, seg = pb.getCameraImage(
            width, height, view, proj, renderer=pb.ER_TINY_RENDERER, flags=flags, physicsClientId=self._record.cid
        )
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
        return rgba, np.asarray(seg, dtype=np.int64).reshape(height, width) if segmentation else None

    def camera_image(
        self,
        width: int,
        height: int,
        view: Sequence[float],
        projection: Sequence[float],
        segmentation: bool,
        behind: int = -1,
        cull: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """One ``getCameraImage``.

        The renderer is TinyRenderer unless :meth:`use_egl` loaded the EGL plugin. TinyRenderer transforms every
        triangle of every shown visual, in view or not, so some bodies are hidden for the frame (made fully
        transparent, which it skips; the images are the same, tests/sensors/test_camera_culling.py):

        * ``behind``, a body that lies wholly behind the camera (the robot carrying it). TinyRenderer rasterises
          the projection of its triangles that reach in front of the eye over the whole viewport, so such a body
          costs a large share of a frame while contributing no pixel (docs/design-notes.md#camera-frames).
        * with ``cull``, and TinyRenderer, the static bodies ``culler.outside_view`` names.

        Args:
            width, height: image size in pixels.
            view, projection: OpenGL matrices, column-major (16 values each; the view's translation in metres).
            segmentation: also return body ids per pixel.
            behind: id of a body wholly behind the camera, hidden for the frame (-1: none).
            cull: hide, for the frame, the static bodies the camera cannot show.

        Returns:
            RGB (height, width, 3) uint8; the raw depth buffer (height, width) in [0, 1]; with ``segmentation``, the
            body id per pixel (height, width), -1 where there is none, else None.

        Raises:
            RuntimeError: this Sim has no visuals.
        """
        self._check_visuals()
        flags = pb.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX if segmentation else pb.ER_NO_SEGMENTATION_MASK
        colours = self._visual_colours(behind) if behind >= 0 else []
        tiny = self._renderer == pb.ER_TINY_RENDERER
        culled = self._record.culler.outside_view(view, projection, width, height) if cull and tiny else []
        for link, _ in colours:
            pb.changeVisualShape(behind, link, rgbaColor=_INVISIBLE, physicsClientId=self._record.cid)
        for body in culled:
            pb.changeVisualShape(body, -1, rgbaColor=_INVISIBLE, physicsClientId=self._record.cid)
        try:
            _, _, rgba, depth, seg = pb.getCameraImage(
                width, height, view, projection, renderer=self._renderer, flags=flags, physicsClientId=self._record.cid
            )
        finally:
            for link, colour in colours:
                pb.changeVisualShape(behind, link, rgbaColor=colour, physicsClientId=self._record.cid)
            for body in culled:
                pb.changeVisualShape(body, -1, rgbaColor=self._record.culler.colour(body),
                                     physicsClientId=self._record.cid)
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]
        depth = np.asarray(depth, dtype=np.float64).reshape(height, width)
        if not segmentation:
            return rgb, depth, None
        seg = np.asarray(seg, dtype=np.int64).reshape(height, width)
        return rgb, depth, np.where(seg >= 0, seg & ((1 << 24) - 1), -1)  # low 24 bits: the body id

    def ray_cast_image(
        self, width: int, height: int, eye: np.ndarray, axes: np.ndarray, intrinsics: tuple[float, float, float, float],
        near: float, far: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Depth and body id per pixel centre, by casting rays against the exact shapes of the record's primitives (the
        shown boxes, cylinders, ground and markers; robots are not drawn). Needs no visuals and no pybullet call.

        Args:
            width, height: image size in pixels.
            eye: (3,) camera centre, world frame, metres.
            axes: (3, 3) rows: the camera's forward, right and down (image rows grow downwards) in world coordinates.
            intrinsics: (fx, fy, cx, cy) in pixels, pixel centres at integer coordinates.
            near, far: metres; only surfaces with depth in [near, far) are seen.

        Returns:
            Depth along the optical axis (height, width) in metres, 0 where nothing is seen; the body id per pixel
            (height, width), -1 where there is none, ``primitives.BACKDROP_ID`` where an obstacle has no body (a
            large scene's far obstacle, out of the physics world).
        """
        bodies, kinds, centres, rotations, halves = self._record.primitives.arrays()
        depth, hit = np.empty((height, width)), np.empty((height, width), dtype=np.int64)
        cast_depth(np.asarray(eye, dtype=float), np.ascontiguousarray(axes, dtype=float), *intrinsics, near, far,
                   kinds, centres, rotations, halves, depth, hit)
        ids = np.full_like(hit, -1)
        seen = hit >= 0
        ids[seen] = bodies[hit[seen]]
        return depth, ids

    def _check_visuals(self) -> None:
        if not self._record.visuals:
            raise RuntimeError("this Sim was made with visuals=False: its obstacles have no visual shapes to draw")

    def _visual_colours(self, body: int) -> list[tuple[int, tuple]]:
        """(link, rgba) of each link of ``body`` with a visual shape (read once, cached).

        Raises:
            ValueError: a link has visual shapes of several colours: pybullet's ``changeVisualShape`` ignores its
                shape index, so they could not get their colours back (:meth:`paint` gives them one).
        """
        if body not in self._record.colours:
            shapes = pb.getVisualShapeData(body, physicsClientId=self._record.cid)
            colours = dict.fromkeys((data[1], data[7]) for data in shapes)  # (link, colour) pairs, once each
            links = [link for link, _ in colours]
            if len(set(links)) != len(links):
                raise ValueError(f"body {body} has a link with visual shapes of several colours; paint it one colour")
            self._record.colours[body] = list(colours)
        return self._record.colours[body]

    def paint(self, body: int, rgba: Sequence[float]) -> None:
        """Give every visual shape of ``body`` the colour ``rgba`` (channels in [0, 1]); a link made of several
        visual shapes (a merged rigid body's base) can only be hidden and shown again in one colour."""
        for link in range(-1, pb.getNumJoints(body, physicsClientId=self._record.cid)):
            pb.changeVisualShape(body, link, rgbaColor=rgba, physicsClientId=self._record.cid)
        self._record.colours.pop(body, None)

    def use_egl(self) -> None:
        """Render camera images with the EGL (OpenGL, headless) plugin instead of TinyRenderer.

        Raises:
            RuntimeError: the plugin does not load on this machine (no EGL driver).
        """
        egl = importlib.util.find_spec("eglRenderer")
        plugin = -1
        if egl is not None and egl.origin:
            with quiet_c_output():
                plugin = pb.loadPlugin(egl.origin, "_eglRendererPlugin", physicsClientId=self._record.cid)
        if plugin < 0:
            raise RuntimeError("camera_renderer='egl': the pybullet EGL plugin did not load (no EGL driver?)")
        self._renderer = pb.ER_BULLET_HARDWARE_OPENGL

    def follow_camera(self, target: Sequence[float], distance: float, yaw_deg: float, pitch_deg: float) -> None:
        """Point the GUI camera (render_mode="human") at ``target`` (metres) from ``distance`` metres away, turned by
        ``yaw_deg`` and ``pitch_deg`` degrees."""
        pb.resetDebugVisualizerCamera(distance, yaw_deg, pitch_deg, target, physicsClientId=self._record.cid)
