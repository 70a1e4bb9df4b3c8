"""The hard-case catalogue's scenes and runs (docs/hard-cases.md): the situations where simulators go wrong, set up
and measured one way for the tests that hold each case (tests/hard_cases/) and for the catalogue's table
(``python -m benchmarks.hard_cases.catalogue``), which runs short versions of them beside their steps/s.

One module per case, named as its test: :mod:`.standstill`, :mod:`.wedging`, :mod:`.sensor_edges`,
:mod:`.movable_clutter`, :mod:`.large_scenes`, :mod:`.memory`, :mod:`.long_runs`, :mod:`.tunneling`, :mod:`.scale`
and :mod:`.penetration_depth`; :mod:`.stepping` holds what the runs that step an env share.

These measure pybullet's own answers as well as the envs' (launched bodies, contact points, translated worlds), so
unlike the env parts some of them call pybullet directly, through :mod:`clutter_gym.sim`'s ``pb``.
"""
