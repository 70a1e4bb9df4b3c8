"""Shortest-path distance to the goal around the clutter, for reward shaping that has no local minima.

The straight-line distance to the goal rewards driving into a U of obstacles; the path distance does not: it is
the length of the shortest 16-connected grid path through cells where the robot's footprint fits (clearance
above its radius), computed once per episode by Dijkstra from the goal cell. Cells the footprint does not fit
in (the robot touching an obstacle) take the value of the nearest reachable cell plus the distance to it, so
the field is finite everywhere and a robot pushed against an obstacle still has a well-defined progress.

For the optional ``subgoal`` observation a second search plans the path a global planner on a known map would
hand a local controller: shortest on a costmap whose cost per metre rises from 1 to ``1 + INFLATION_COST`` as the
footprint's clearance drops from ``plan_margin`` to 0 (a navigation stack's inflation layer), so the path keeps
off obstacles where there is room to. The subgoal is the point a fixed length ahead on that path.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from clutter_gym.worlds.floor.grid import scene_clearance
from clutter_gym.worlds.floor.scene import Scene
from clutter_gym.worlds.floor.spec import ClutterSpec
from clutter_gym.worlds.grid_search import search_grid
from clutter_gym.worlds.path_field import GridPathField

# Forward moves (di, dj) of the 16-neighbourhood (the other eight are their mirror images), each with
# the cells its segment passes through, which must be free too. 16 neighbours bound the path-length error in
# open space to 2.7% (8 neighbours: 8.2%).
_MOVES = (
    ((1, 0), ()), ((0, 1), ()),
    ((1, 1), ((1, 0), (0, 1))), ((1, -1), ((1, 0), (0, -1))),
    ((2, 1), ((1, 0), (1, 1))), ((1, 2), ((0, 1), (1, 1))),
    ((2, -1), ((1, 0), (1, -1))), ((1, -2), ((0, -1), (1, -1))),
)


#: Cost per metre at zero clearance on the planner's costmap, on top of the 1 every metre costs.
INFLATION_COST = 4.0


class PathDistance(GridPathField):
    """Path length from a point to the goal, metres (bilinear in the cell-centre values), and with a
    ``plan_margin`` the planner's path and the point a given length along it (:meth:`path`, :meth:`waypoint`).

    Args:
        scene: the episode's layout (obstacles and goal).
        spec: arena size and grid resolution.
        robot_radius: footprint radius, metres.
        plan_margin: None, or the clearance (metres beyond the footprint) below which the planner behind
            :meth:`waypoint` charges extra; None skips that search.
    """

    def __init__(self, scene: Scene, spec: ClutterSpec, robot_radius: float, plan_margin: float | None = None) -> None:
        centres = spec.cell_centres
        self._res = float(centres[1] - centres[0])
        super().__init__((centres, centres), self._res, scene.goal)
        self._origin, self._top = float(centres[0]), float(len(centres) - 1)  # first centre, last index
        reach = self._res if plan_margin is None else max(self._res, plan_margin)
        clearance = scene_clearance(scene, spec, cap=robot_radius + reach)
        goal_cell = self._nearest_cell(scene.goal)
        self._distance, _ = _dijkstra_from(goal_cell, clearance, robot_radius, self._res)
        self._goal_cell = goal_cell[0] * len(centres) + goal_cell[1]
        if plan_margin is not None:
            shortfall = np.clip((robot_radius + plan_margin - clearance) / max(plan_margin, 1e-9), 0.0, 1.0)
            _, self._next = _dijkstra_from(goal_cell, clearance, robot_radius, self._res,
                                           1.0 + INFLATION_COST * shortfall**2)

    def _nearest_cell(self, point: tuple[float, ...]) -> tuple[int, ...]:
        n = self._shape[0]
        return tuple(int(np.clip(round((p - self._origin) / self._res), 0, n - 1)) for p in point)

    def _entry(self, point: tuple[float, ...]) -> int:
        """The reachable cell nearest the cell holding ``point``: the planned path starts at its centre."""
        i, j = self._nearest_cell(point)
        return int(self._filled[1][i * self._shape[1] + j])

    def __call__(self, x: float, y: float) -> float:
        top = self._top
        fx = min(max((x - self._origin) / self._res, 0.0), top)
        fy = min(max((y - self._origin) / self._res, 0.0), top)
        i, j = min(int(fx), int(top) - 1), min(int(fy), int(top) - 1)
        tx, ty = fx - i, fy - j
        v = self.values
        grid = ((1 - tx) * (1 - ty) * v[i, j] + tx * (1 - ty) * v[i + 1, j]
                + (1 - tx) * ty * v[i, j + 1] + tx * ty * v[i + 1, j + 1])
        # The grid path can only be longer than the straight line; near the goal it is coarse, so clamp.
        return max(float(grid), math.hypot(x - self._goal[0], y - self._goal[1]))


def _dijkstra_from(source: tuple[int, int], clearance: np.ndarray, radius: float, res: float,
                   cost: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(n, n) shortest 16-connected path length from ``source`` through cells of clearance above ``radius`` (the
    source counts as one; inf where unreachable), and (n * n,) each cell's next cell on its path to ``source``
    (negative where there is none).

    ``cost`` (n, n), if given, weighs each metre of a move by the mean cost of the cells it joins."""
    n = clearance.shape[0]
    moves, lengths, through = _stencil(res)
    clear = clearance.copy()
    clear[source] = np.inf
    distance, after = search_grid(clear, np.full(len(moves), radius), moves, lengths,
                                  np.array([source[0] * n + source[1]]), np.zeros(1), through, cost)
    return distance.reshape(n, n), after


@functools.cache
def _stencil(res: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 16 moves both ways (cells), their lengths (metres) and the cells each one crosses (steps from its
    start, the start itself filling the rows of moves that cross fewer than two)."""
    forward = [(move, through) for move, through in _MOVES]
    backward = [((-di, -dj), tuple((ti - di, tj - dj) for ti, tj in through)) for (di, dj), through in _MOVES]
    both = forward + backward
    crossed = np.zeros((len(both), 2, 2), dtype=np.int64)
    for k, (_, through) in enumerate(both):
        for c, cell in enumerate(through):
            crossed[k, c] = cell
    return (np.array([move for move, _ in both]), res * np.array([math.hypot(*move) for move, _ in both]), crossed)
