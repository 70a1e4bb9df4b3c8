"""Seeded ClutterFly volumes with a reachability guarantee for a sphere of the drone's bounding radius.

Sampling, per attempt:

1. Obstacles until their summed volume reaches ``obstacle_density`` of the volume, each of one of four kinds
   (``VolumeSpec.shape_probs``): vertical poles (tree trunks: cylinders from the floor to the top), boxes (on the
   floor or hanging), horizontal beams (long boxes of square section at a random height and yaw) and walls from
   floor to top with one opening (a door at the floor or a window above it; see :func:`wall_with_opening`). Sizes
   take one of ``size_levels`` evenly spaced values per range, so the body pool covers every layout with a bounded
   set of shapes.
2. The clearance grid of ``worlds/volume/grid.py``: exact signed distance from each cell centre to the nearest
   obstacle or face of the volume.
3. A cell is *free* when its clearance exceeds r + h / 2 (r the robot's radius, h the largest cell edge); by the
   Lipschitz argument in ``worlds/volume/grid.py`` a 6-connected chain of free cells is a collision-free path for
   the sphere, so start and goal in one 6-connected free component (``scipy.ndimage.label``) are reachable.
4. Start and goal are centres of free cells with clearance above r + ``spawn_clearance``, in one component and at
   least ``min_goal_distance`` apart. No such pair: a new attempt.

After ``PLAIN_ATTEMPTS`` failed attempts the generator keeps a corridor clear, as the floor world's does
(``worlds/floor/sample.py``): it draws start, one waypoint and goal first and refuses obstacles (a wall with all its
pieces) that come within ``keep`` = r + max(spawn_clearance, h) + h of the polyline through them. The cells the
polyline crosses then have clearance above r + h / 2 and r + spawn_clearance, so the steps above find start and goal
in one component, and the density is still met elsewhere (unless the corridor leaves too little room for it).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from clutter_gym.datatypes import Obstacle
from clutter_gym.worlds.volume.grid import VolumeGrid, cell_index, clearance_field, free_margin, signed_distance
from clutter_gym.worlds.volume.scene import VolumeScene
from clutter_gym.worlds.volume.spec import VolumeSpec

PLAIN_ATTEMPTS = 5  # attempts at unconstrained clutter before the generator keeps a corridor clear
_BATCH = 32  # obstacles drawn per batch of random numbers
_MAX_REFUSED_BATCHES = 50  # a corridor that leaves too little room for the density ends the sampling early


def wall_with_opening(centre: tuple[float, float], yaw: float, length: float, thickness: float, height: float,
                      opening: tuple[float, float, float, float]) -> tuple[Obstacle, ...]:
    """A wall from the floor to ``height`` split into boxes around one rectangular opening.

    The wall runs along its own x axis (turned by ``yaw`` about +z), centred on ``centre`` (x, y). ``opening`` is
    (start along the wall from its -x end, width, bottom height, height), metres; a bottom of 0 makes a door. The
    pieces are the part left and right of the opening (full height) and those below and above it, each left out
    where it would be empty.
    """
    start, width, bottom, tall = opening
    c, s = math.cos(yaw), math.sin(yaw)
    pieces = []

    def piece(u0: float, u1: float, z0: float, z1: float) -> None:
        if u1 - u0 > 1e-9 and z1 - z0 > 1e-9:
            u = -0.5 * length + 0.5 * (u0 + u1)
            pieces.append(Obstacle("box", (round(u1 - u0, 6), thickness, round(z1 - z0, 6)),
                                   (centre[0] + c * u, centre[1] + s * u), yaw, z0))

    piece(0.0, start, 0.0, height)
    piece(start + width, length, 0.0, height)
    piece(start, start + width, 0.0, bottom)
    piece(start, start + width, bottom + tall, height)
    return tuple(pieces)


def _corridor(rng: np.random.Generator, spec: VolumeSpec, keep: float, far: float) -> np.ndarray | None:
    """(3, 3) start, waypoint and goal, each ``keep`` inside the volume's faces (at the middle of an axis shorter than
    twice that: a volume lower than it, whose middle is still clear enough to start from), start and goal ``far``
    apart; None when the volume is too small for such a pair."""
    low = np.array([-0.5 * spec.size[0], -0.5 * spec.size[1], 0.0]) + keep
    high = np.array([0.5 * spec.size[0], 0.5 * spec.size[1], spec.size[2]]) - keep
    middle = 0.5 * (low + high)
    low, high = np.minimum(low, middle), np.maximum(high, middle)
    ends = rng.uniform(low, high, size=(64, 2, 3))
    apart = np.flatnonzero(np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1) >= far)
    if apart.size == 0:
        return None
    start, goal = ends[apart[0]]
    return np.array([start, rng.uniform(low, high), goal])


def _polyline_points(polyline: np.ndarray, step: float) -> np.ndarray:
    """(k, 3) points along ``polyline`` no more than ``step`` apart, ends included."""
    parts = []
    for a, b in zip(polyline[:-1], polyline[1:]):
        n = max(1, math.ceil(np.linalg.norm(b - a) / step))
        parts.append(a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a))
    return np.concatenate(parts)


def _obstacle_group(spec: VolumeSpec, kind: int, u: np.ndarray, level: np.ndarray) -> tuple[Obstacle, ...]:
    """One obstacle (a wall: its pieces) of ``kind`` (index into :data:`~clutter_gym.worlds.volume.spec.SHAPES`)
    from uniforms ``u`` (6,) in [0, 1) and level indices ``level`` (5,)."""
    values = spec.size_values
    sx, sy, sz = spec.size
    xy = (float((u[0] - 0.5) * sx), float((u[1] - 0.5) * sy))
    yaw = float((2.0 * u[2] - 1.0) * math.pi)
    if kind == 0:  # pole
        radius = float(values["pole_radius"][level[0]])
        return (Obstacle("cylinder", (2 * radius, 2 * radius, sz), xy),)
    if kind == 1:  # box: on the floor or hanging
        side = values["box_side"]
        size = tuple(float(side[i]) for i in level[:3])
        z = 0.0 if u[4] < 0.5 else float(u[3] * (sz - size[2]))
        return (Obstacle("box", size, xy, yaw, z),)
    if kind == 2:  # beam
        length = float(values["beam_length"][level[0]])
        thick = float(values["beam_thickness"][level[1]])
        return (Obstacle("box", (length, thick, thick), xy, yaw, float(u[3] * (sz - thick))),)
    length = float(values["wall_length"][level[0]])
    reach = (min(0.5 * length * abs(math.cos(yaw)), 0.5 * sx), min(0.5 * length * abs(math.sin(yaw)), 0.5 * sy))
    xy = (float((u[0] - 0.5) * (sx - 2 * reach[0])), float((u[1] - 0.5) * (sy - 2 * reach[1])))  # ends inside
    width, tall = (float(values["opening_size"][i]) for i in level[1:3])
    slots = spec.size_levels
    along = round((level[3] + 0.5) / slots * (length - width), 3)  # the opening's start: a level too
    bottom = round(level[4] / max(slots - 1, 1) * (sz - tall), 3)  # level 0 is a door
    return wall_with_opening(xy, yaw, length, spec.wall_thickness, sz, (along, width, bottom, tall))


def _sample_obstacles(rng: np.random.Generator, spec: VolumeSpec, corridor: np.ndarray | None = None,
                      keep: float = 0.0) -> tuple[Obstacle, ...]:
    """Obstacles drawn in batches until their summed volume reaches ``obstacle_density`` of the volume; with a
    ``corridor`` polyline, none that comes within ``keep`` metres of it."""
    target = spec.obstacle_density * spec.volume
    step = 0.5 * float(spec.cell_size.min())
    points = _polyline_points(corridor, step) if corridor is not None else None
    obstacles: list[Obstacle] = []
    covered, refused = 0.0, 0
    while covered < target and refused < _MAX_REFUSED_BATCHES:
        kinds = rng.choice(len(spec.shape_probs), size=_BATCH, p=spec.shape_probs)
        uniforms = rng.uniform(size=(_BATCH, 6))
        levels = rng.integers(0, spec.size_levels, size=(_BATCH, 5))
        placed = len(obstacles)
        for kind, u, level in zip(kinds, uniforms, levels):
            if covered >= target:
                break
            group = _obstacle_group(spec, int(kind), u, level)
            if points is not None and any(  # every point of the polyline is within step / 2 of a sample
                signed_distance(o, points[:, 0], points[:, 1], points[:, 2]).min() < keep + 0.5 * step for o in group
            ):
                continue
            obstacles.extend(group)
            covered += sum(o.volume for o in group)
        refused = refused + 1 if len(obstacles) == placed else 0
    return tuple(obstacles)


def _centre(flat: int, spec: VolumeSpec, shape: tuple[int, int, int]) -> np.ndarray:
    """(3,) centre (metres) of the cell with flat index ``flat`` on a grid of ``shape``."""
    return np.array([c[i] for c, i in zip(spec.cell_centres, np.unravel_index(flat, shape))])


def sample_volume_scene(rng: np.random.Generator, spec: VolumeSpec, robot_radius: float) -> VolumeScene:
    """A random volume whose goal is reachable for a sphere of ``robot_radius`` metres (see the module docstring).

    Start (x, y, z, yaw) and goal (x, y, z) are cell centres; every random number comes from ``rng``.

    Raises:
        RuntimeError: no valid layout in ``spec.max_attempts`` tries (too dense for the robot).
    """
    h = 2.0 * free_margin(spec)
    free = robot_radius + 0.5 * h
    spawn = robot_radius + spec.spawn_clearance
    keep = robot_radius + max(spec.spawn_clearance, h) + h
    far = spec.min_goal_distance * max(spec.size[:2])
    for attempt in range(spec.max_attempts):
        corridor = _corridor(rng, spec, keep, far + math.sqrt(3.0) * h) if attempt >= PLAIN_ATTEMPTS else None
        obstacles = _sample_obstacles(rng, spec, corridor, keep)
        field = clearance_field(obstacles, spec, keep)
        labels, _ = ndimage.label(field > free)
        flat_labels = labels.ravel()
        spawn_cells = np.flatnonzero((field.ravel() > spawn) & (flat_labels > 0))
        if spawn_cells.size < 2:
            continue
        if corridor is None:
            start_cell = int(rng.choice(spawn_cells))
        else:
            start_cell = int(np.ravel_multi_index(cell_index(corridor[0], spec), field.shape))
            if start_cell not in spawn_cells:
                continue
        start = _centre(start_cell, spec, field.shape)
        centres = np.stack([c[i] for c, i in zip(spec.cell_centres, np.unravel_index(spawn_cells, field.shape))], 1)
        goals = spawn_cells[(flat_labels[spawn_cells] == flat_labels[start_cell])
                            & (np.linalg.norm(centres - start, axis=1) >= far)]
        if corridor is not None:  # the far end of the corridor when its cell qualifies, as it does by construction
            end = int(np.ravel_multi_index(cell_index(corridor[2], spec), field.shape))
            goals = goals[goals == end] if np.any(goals == end) else goals
        if goals.size == 0:
            continue
        goal = _centre(int(rng.choice(goals)), spec, field.shape)
        yaw = float(rng.uniform(-math.pi, math.pi))
        field.flags.writeable = False
        return VolumeScene(obstacles, (*map(float, start), yaw), tuple(map(float, goal)),
                           VolumeGrid(spec, keep, field))
    raise RuntimeError(
        f"no volume with a reachable goal in {spec.max_attempts} attempts at obstacle_density="
        f"{spec.obstacle_density} in a {spec.size} m volume for a robot of radius {robot_radius} m; lower the "
        f"density or enlarge the volume"
    )
