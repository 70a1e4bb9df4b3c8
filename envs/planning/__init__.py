"""Planners on a known layout: what a map-based agent or a reference controller is told."""
