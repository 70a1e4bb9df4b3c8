"""95% confidence intervals for evaluation summaries, from scipy: Wilson for rates, Student t for means."""

from __future__ import annotations

import numpy as np
from scipy import stats


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (good at 0% and 100%, unlike the normal approximation)."""
    if n <= 0:
        raise ValueError(f"n must be a positive number of trials, got {n}")
    interval = stats.binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    # At 0 and n the bounds are exactly 0 and 1; the formula gives them only up to rounding.
    low = 0.0 if successes == 0 else float(interval.low)
    high = 1.0 if successes == n else float(interval.high)
    return low, high


def mean_interval(values: np.ndarray, confidence: float = 0.95) -> tuple[float, float]:
    """Student-t interval of the mean; a single value (or zero spread) gives a zero-width interval."""
    values = np.asarray(values, dtype=float)
    mean = float(values.mean())
    if values.size < 2 or float(values.std()) == 0.0:
        return mean, mean
    interval = stats.ttest_1samp(values, 0.0).confidence_interval(confidence_level=confidence)
    return float(interval.low), float(interval.high)
