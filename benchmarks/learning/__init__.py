"""Learning: trained and scripted policies against their targets.

``main_job`` (PPO seeds of the main job against its target), ``baselines`` (the baseline tables: scripted and
trained policies at several clutter levels and noise profiles), ``fly_harsh`` (which part of ``harsh`` breaks
ClutterFly's flyer, and what holds it), ``nav_diagnosis`` (why a ClutterNav-v1 policy fails where the potential
field succeeds) and ``run_curves`` (training curves of several runs side by side).
"""
