"""Rendering as a stage: while a render mode is set, every reset and step notes where the robot's focus is (the
trail the frames draw), and :meth:`RenderTrail.frame` draws the arena's view with the robot and the goal ringed.
In ``"human"`` mode the GUI's camera follows the robot after every reset and step. Rendering reads the world and
draws nothing into it: it never changes a trajectory."""

from __future__ import annotations

import weakref
from collections import deque
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from clutter_gym.datatypes import Obstacle, RobotState
from clutter_gym.stages.base import Stage
from clutter_gym.util.camera_view import CameraView, orbit_angles
from clutter_gym.util.overlay import draw_marks

if TYPE_CHECKING:
    from clutter_gym.core import ClutterEnv

TRAIL_LENGTH = 400  # control steps of the robot's path that rgb_array frames draw


class RenderTrail(Stage):
    """The trail of the robot's focus (:attr:`trail`, world frame) and the frames drawn over it."""

    def __init__(self, human: bool = False) -> None:
        self.trail: deque[np.ndarray] = deque(maxlen=TRAIL_LENGTH)
        self._radius = 0.0
        self._human = human

    def bind(self, env: ClutterEnv) -> None:
        self._env = weakref.proxy(env)  # no reference cycle: a dropped env is freed at once, its physics server too

    def episode_start(self, obstacles: Sequence[Obstacle], bodies: Sequence[int], rng: np.random.Generator) -> bool:
        self.trail.clear()
        return True

    def checked(self, state: RobotState) -> None:
        centre, self._radius = self._env.robot.render_focus(state)
        self.trail.append(np.array(centre, dtype=float))
        if self._human:
            self.frame(human=True)

    def view(self) -> CameraView:
        """The camera of the next frame, chosen by the arena (``Arena.render_camera``) from where the robot's focus
        and the goal are."""
        env = self._env
        focus, goal = self._focus_and_goal()
        eye, target = env.arena.render_camera(env.sim, focus, goal)
        width, height = env.render_size
        return CameraView((float(eye[0]), float(eye[1]), float(eye[2])),
                          (float(target[0]), float(target[1]), float(target[2])), width, height)

    def frame(self, human: bool) -> np.ndarray | None:
        """rgb_array: the frame of :meth:`view` (H, W, 3) uint8, the robot and the goal ringed and the trail drawn
        (:func:`clutter_gym.util.overlay.draw_marks`); ``human``: points the GUI camera the same way (None)."""
        env, view = self._env, self.view()
        if human:
            env.sim.rendering.follow_camera(view.target, *orbit_angles(view.eye, view.target))
            return None
        frame = env.sim.rendering.render(view.width, view.height, view.eye, view.target, view.fov_deg)
        focus, goal = self._focus_and_goal()
        return draw_marks(frame, view, (focus, self._radius), (goal, env.task.success_radius), self.trail)

    def _focus_and_goal(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's focus and the goal marker's centre, world frame (before the first reset: where the robot
        stands, for both; so too after a reset that failed, which left no scene)."""
        env = self._env
        if not self.trail or env.scene is None:
            centre, self._radius = env.robot.render_focus(env.robot.state())
            return np.asarray(centre, dtype=float), np.asarray(centre, dtype=float)
        return self.trail[-1], np.asarray(env.task.marker_position(env.scene), dtype=float)
