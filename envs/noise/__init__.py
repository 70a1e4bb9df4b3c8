"""Sensor, actuation and dynamics noise: pure functions of (clean value, rng, params), named profiles as data."""
