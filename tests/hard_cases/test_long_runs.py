"""Long runs (``python -m benchmarks.hard_cases.long_runs``): random steps in every env, profile and fidelity level
stay finite; resets and make/close cycles hold memory and reset time flat.

The default run checks the pieces on short stretches; the ``slow`` ones run a scaled-down long run (48 cells of
random steps, 5,000 resets, 100 make/close cycles). Bounds: no non-finite value at all; memory growth per reset
under 1 KB over the second half (the leak this catalogue fixed cost 7-240 KB per reset), per make/close cycle under
50 KB (the catalogue's 50 MB over 1,000 cycles); the reset time of the last block within 1.5x of the first (a
reset that slowed with the pool or the world would grow far past that).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from benchmarks.hard_cases.scenes.long_runs import (
    count_nonfinite,
    cycles_run,
    growth_per,
    random_steps,
    resets_run,
    steps_run,
)
from clutter_gym import ENV_IDS
from clutter_gym.collision import FIDELITY_LEVELS
from clutter_gym.noise.profiles import PROFILE_NAMES

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/statm")


class Collect:
    """A stand-in for the multiprocessing queue the long-run parts put their result on."""

    def put(self, value: object) -> None:
        self.value = value


def test_count_nonfinite_finds_every_nan_and_inf_in_nested_values():
    value = {"a": np.array([1.0, np.nan, np.inf]), "b": (1.0, [float("-inf"), 2]), "c": "text", "d": True,
             "e": np.float32(np.nan), "f": np.arange(3), "g": None, "h": {"i": [np.array([[np.nan]])]}}
    assert count_nonfinite(value) == 5
    assert count_nonfinite({"clean": np.ones(4), "n": 3, "x": 0.5}) == 0


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_random_steps_under_the_harshest_profile_stay_finite(env_id):
    cell = random_steps(env_id, "harsh", "mesh", 60, seed=1)
    assert (cell.steps, cell.nonfinite) == (60, 0) and cell.episodes >= 1 and cell.steps_per_s > 0


def test_growth_is_taken_over_the_second_half():
    rows = [(10, 100.0, 1.0), (20, 150.0, 1.0), (30, 150.0, 1.0), (40, 151.0, 1.0)]
    assert growth_per(rows) == pytest.approx(1024 / 20)  # 1 MiB over the last 20, the warm-up's 50 MiB left out


@pytest.mark.slow
@linux_only
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_profile_and_fidelity_level_stays_finite_with_flat_memory(env_id):
    out = Collect()
    steps_run(env_id, 400, out)
    cells = out.value
    assert len(cells) == len(PROFILE_NAMES) * len(FIDELITY_LEVELS)
    assert sum(c.nonfinite for c in cells) == 0
    half = len(cells) // 2
    assert cells[-1].resident_mib - cells[half - 1].resident_mib < 20  # 12 envs made, stepped and closed


@pytest.mark.slow
@linux_only
def test_resets_hold_memory_and_reset_time_flat():
    out = Collect()
    resets_run("ClutterNav-v1", 5_000, out)
    rows = out.value
    assert growth_per(rows) < 1.0
    assert rows[-1][2] < 1.5 * rows[0][2]


@pytest.mark.slow
@linux_only
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_make_close_cycles_hold_memory_flat(env_id):
    out = Collect()
    cycles_run(env_id, 100, out)
    _, rows = out.value
    assert growth_per(rows) < 50.0
