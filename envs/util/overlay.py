"""Marks drawn over an ``rgb_array`` frame so that the robot and its goal can always be found: a ring on each, the
robot's recent trail, and an arrow on the frame's edge towards a goal out of view.

Pure drawing on numpy images with pillow's ImageDraw, placed with :class:`~clutter_gym.util.camera_view.CameraView`
(the camera the frame was rendered from); no simulator. Rings are drawn whatever stands in front of the point, so
an occluded goal is still marked.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw

from clutter_gym.util.camera_view import CameraView

ROBOT_COLOUR = (255, 40, 200)  # magenta: no obstacle, floor or robot is drawn in it
GOAL_COLOUR = (255, 214, 0)  # gold
OUTLINE = (20, 20, 20)
#: Frame height the pixel sizes below are given for; larger frames scale them up.
REFERENCE_HEIGHT = 240
LEAST_RING_PX = 7.0  # a ring never shrinks below this radius, so a far robot or goal is still marked
RING_PX = 2  # ring line width
TRAIL_PX = 2


def draw_marks(frame: np.ndarray, view: CameraView, robot: tuple[np.ndarray | Sequence[float], float],
               goal: tuple[np.ndarray | Sequence[float], float],
               trail: np.ndarray | Sequence[np.ndarray | Sequence[float]]) -> np.ndarray:
    """``frame`` (H, W, 3) uint8 with the marks drawn over it, as a new array.

    Args:
        frame: the picture ``view`` took.
        view: its camera.
        robot: (centre, radius in metres) of the robot part to ring: its base, or an arm's hand.
        goal: (centre, radius in metres) of the goal region.
        trail: (n, 3) the robot centre's recent positions, oldest first, world frame; drawn as a line that fades
            with age.
    """
    scale = frame.shape[0] / REFERENCE_HEIGHT
    image = Image.fromarray(np.ascontiguousarray(frame[:, :, :3], dtype=np.uint8))
    trail = np.asarray(trail, dtype=float).reshape(-1, 3)
    if len(trail) > 1:
        image = _draw_trail(image, view, trail, scale)
    draw = ImageDraw.Draw(image)
    for (centre, radius), colour in ((goal, GOAL_COLOUR), (robot, ROBOT_COLOUR)):
        pixel, in_front = view.project([centre])
        if in_front[0] and _inside(pixel[0], view, 0.0):
            size = max(LEAST_RING_PX * scale, 1.3 * radius * float(view.pixels_per_metre([centre])[0]) + 2.0 * scale)
            _ring(draw, pixel[0], size, colour, max(1, round(RING_PX * scale)))
        else:
            _edge_arrow(draw, view, pixel[0], bool(in_front[0]), colour, scale)
    return np.asarray(image, dtype=np.uint8)


def _ring(draw: ImageDraw.ImageDraw, centre: np.ndarray, radius: float, colour: Sequence[int], width: int) -> None:
    """A ring with a thin dark border on either side, so that it reads on light and dark backgrounds."""
    c, r = float(centre[0]), float(centre[1])
    outer = radius + width + 1
    draw.ellipse((c - outer, r - outer, c + outer, r + outer), outline=OUTLINE, width=width + 2)
    draw.ellipse((c - radius - width, r - radius - width, c + radius + width, r + radius + width),
                 outline=tuple(colour), width=width)


def _draw_trail(image: Image.Image, view: CameraView, trail: np.ndarray, scale: float) -> Image.Image:
    """The trail as a polyline whose opacity grows from its oldest point to its newest; segments with an end behind
    the camera or far outside the frame are left out."""
    pixels, in_front = view.project(trail)
    usable = in_front & np.all(np.abs(pixels) < 4 * max(view.width, view.height), axis=1)
    layer = Image.new("RGBA", image.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(layer)
    width = max(1, round(TRAIL_PX * scale))
    n = len(trail)
    for i in range(n - 1):
        if usable[i] and usable[i + 1]:
            alpha = int(60 + 180 * (i + 1) / (n - 1))
            draw.line([tuple(pixels[i]), tuple(pixels[i + 1])], fill=(*ROBOT_COLOUR, alpha), width=width)
    return Image.alpha_composite(image.convert("RGBA"), layer).convert("RGB")


def _inside(pixel: np.ndarray, view: CameraView, margin: float) -> bool:
    return bool(margin <= pixel[0] <= view.width - 1 - margin and margin <= pixel[1] <= view.height - 1 - margin)


def _edge_arrow(draw: ImageDraw.ImageDraw, view: CameraView, pixel: np.ndarray, in_front: bool,
                colour: Sequence[int], scale: float) -> None:
    """A triangle on the frame's edge pointing towards a point out of view (a point behind the camera projects
    mirrored through the centre, so its direction is turned round)."""
    centre = np.array([(view.width - 1) / 2.0, (view.height - 1) / 2.0])
    direction = pixel - centre if in_front else centre - pixel
    norm = float(np.linalg.norm(direction))
    direction = direction / norm if norm > 1e-9 else np.array([0.0, 1.0])
    size = 9.0 * scale
    margin = size + 2.0
    half = np.array([view.width / 2.0 - margin, view.height / 2.0 - margin])
    reach = float(np.min(half / np.maximum(np.abs(direction), 1e-9)))  # to the inset frame's border
    tip = centre + reach * direction
    side = np.array([-direction[1], direction[0]])
    base = tip - size * direction
    corners = [tuple(tip), tuple(base + 0.6 * size * side), tuple(base - 0.6 * size * side)]
    draw.polygon(corners, fill=tuple(colour), outline=OUTLINE)
