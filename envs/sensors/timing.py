"""Each sensor's timing at run time: sample-and-hold at its rate, then a delay line of its latency.

The parameters are :class:`clutter_gym.noise.timing.SensorTiming` (part of a noise profile); this module holds the
state that runs them, one clock per sensor, ticking once per control step.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from clutter_gym.datatypes import RobotState
from clutter_gym.interfaces import Sensor
from clutter_gym.noise.timing import SensorTiming
from clutter_gym.sim import Sim


class SampleHoldDelay:
    """Sample-and-hold at ``rate_hz`` followed by a ``latency_steps`` delay line, ticking once per control step.

    Args:
        timing: rate and latency.
        control_dt: control period, seconds.
    """

    def __init__(self, timing: SensorTiming, control_dt: float) -> None:
        self.timing = timing
        self._period = 0.0 if timing.rate_hz == 0.0 else 1.0 / timing.rate_hz
        self._dt = control_dt
        self._line: deque[Any] = deque(maxlen=timing.latency_steps + 1)
        self._since_update = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        """Empty the line and draw this episode's phase (nothing is drawn when the sensor runs every step)."""
        self._line.clear()
        if self._period > self._dt:
            self._since_update = float(rng.uniform(0.0, self._period))

    def due(self) -> bool:
        """Advance one control step; True when the sensor takes a new reading in it (always on the first)."""
        if not self._line or self._period <= self._dt:
            return True  # the first reading of an episode, or a sensor at least as fast as the control loop
        self._since_update += self._dt
        if self._since_update + 1e-9 >= self._period:
            self._since_update -= self._period
            return True
        return False

    def push(self, reading: Any | None) -> Any:
        """Record this step's reading (None = held) and return the one that arrives now.

        The first reading of an episode fills the whole line, so the first observations are not blank.
        """
        if reading is None:
            reading = self._line[-1]
        elif not self._line:
            self._line.extend([reading] * (self.timing.latency_steps + 1))
        self._line.append(reading)
        return self._line[0]


def timed_reading(sensor: Sensor, clock: SampleHoldDelay, sim: Sim, state: RobotState,
                  rng: np.random.Generator) -> tuple[dict[str, np.ndarray], dict[str, Any], Any]:
    """One control step of ``sensor`` behind its ``clock``: the (observation, info, reading) that arrive now, the
    reading in the sensor's physical units (what a filter downstream of the sensor gets).

    The sensor reads when its clock makes a reading due (or every step, if it must keep its own state current);
    a held or delayed reading was handed out before, so its observation and info entries come back as copies.
    """
    due = clock.due()
    reading = sensor.read(sim, state, rng) if due or sensor.read_every_step else None
    fresh = (sensor.observe(reading), sensor.info(reading), reading) if due else None
    delivered = clock.push(fresh)
    if delivered is not fresh:
        obs, info, reading = delivered
        delivered = ({k: np.copy(v) for k, v in obs.items()}, {k: np.copy(v) for k, v in info.items()}, reading)
    return delivered


class TimedSensors:
    """An env's sensors, each behind its clock, and the reading each delivered last (:attr:`readings`, in the
    sensors' order: what a filter downstream of a sensor, such as the collision monitor, acts on).

    Args:
        sensors: read in order.
        timing: each sensor's timing, by name (a noise profile's ``timing``); a sensor it does not name reads every
            control step, without latency.
        control_dt: control period, seconds.
    """

    def __init__(self, sensors: Sequence[Sensor], timing: Mapping[str, SensorTiming], control_dt: float) -> None:
        self.sensors = tuple(sensors)
        self.clocks = tuple(SampleHoldDelay(timing.get(s.name) or SensorTiming(), control_dt) for s in self.sensors)
        self.readings: list[Any] = [None] * len(self.sensors)

    def reset(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> None:
        for sensor, clock in zip(self.sensors, self.clocks):
            sensor.reset(sim, state, rng)
            clock.reset(rng)

    def read(self, sim: Sim, state: RobotState, rng: np.random.Generator) -> tuple[dict[str, np.ndarray],
                                                                                     dict[str, Any]]:
        """One control step of every sensor: the observation and info entries that arrive now."""
        obs: dict[str, np.ndarray] = {}
        info: dict[str, Any] = {}
        for i, (sensor, clock) in enumerate(zip(self.sensors, self.clocks)):
            sensor_obs, sensor_info, self.readings[i] = timed_reading(sensor, clock, sim, state, rng)
            obs.update(sensor_obs)
            info.update(sensor_info)
        return obs, info
