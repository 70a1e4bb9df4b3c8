"""Training on a fixed set of layouts: each env resets from its own few seeds, drawn once.

A layout whose per-reset work is costly (the ClutterReach subgoal plans a joint-space path on it) is then paid
for once per layout, not once per episode: the env keeps what it planned. The policy still meets many layouts
(``n_envs`` times the pool of each env), and is validated and evaluated on held-out ones as always. A training
device only: evaluation, validation and ``load()`` never use it.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

#: Pool seeds are drawn from [POOL_SEEDS, 2 * POOL_SEEDS): above every seed a run or an evaluation takes
#: (those are < 2**31), so a training layout is never an evaluation one.
POOL_SEEDS = 2**32


class LayoutPool(gym.Wrapper):
    """Resets ``env`` with one of ``n_layouts`` seeds, chosen uniformly at every reset.

    The pool and the stream that picks from it are seeded by the first seeded reset (the vector env's seed), so
    a training run is as reproducible as without the pool. A reset with an explicit ``options["scene"]`` passes
    through unchanged.

    Args:
        env: the env to wrap.
        n_layouts: layouts in the pool, >= 1.
    """

    def __init__(self, env: gym.Env, n_layouts: int) -> None:
        if not (isinstance(n_layouts, int) and n_layouts >= 1):
            raise ValueError(f"n_layouts must be an integer >= 1, got {n_layouts!r}")
        super().__init__(env)
        self.n_layouts = n_layouts
        self._rng: np.random.Generator | None = None
        self.pool = np.zeros(0, dtype=np.int64)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict]:
        if options and "scene" in options:
            return self.env.reset(seed=seed, options=options)
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
            self.pool = self._rng.integers(POOL_SEEDS, 2 * POOL_SEEDS, size=self.n_layouts)
        return self.env.reset(seed=int(self._rng.choice(self.pool)), options=options)
