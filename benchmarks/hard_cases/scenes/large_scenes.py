"""Large scenes: thousands of small obstacles in the largest ClutterNav arena."""

from __future__ import annotations

import numpy as np

ARENA = 30.0  # metres: the largest arena_size


def grid_scene(n: int, arena: float = ARENA) -> dict:
    """``n`` small boxes and cylinders of three sizes on a jittered grid, the start corner kept clear."""
    rng = np.random.default_rng(n)
    side = int(np.ceil(np.sqrt(n)))
    cells = (np.arange(side) + 0.5) / side * (arena - 1.0) - 0.5 * (arena - 1.0)
    xy = np.stack(np.meshgrid(cells, cells), -1).reshape(-1, 2)[:n] + rng.uniform(-0.1, 0.1, (n, 2))
    obstacles = []
    for k, (x, y) in enumerate(xy):
        if np.hypot(x + 14.0, y) < 1.0:
            continue
        if k % 2:
            obstacles.append({"shape": "cylinder", "radius": (0.05, 0.08, 0.1)[k % 3], "height": 0.5,
                              "position": [float(x), float(y)]})
        else:
            obstacles.append({"shape": "box", "size": [0.1, 0.2, (0.3, 0.5)[k % 4 // 2]],
                              "position": [float(x), float(y)], "yaw": float(k)})
    return {"obstacles": obstacles, "start": [-14.0, 0.0, 0.0], "goal": [-12.0, 0.0]}
