"""Speed and accuracy benchmarks of clutter-gym; results and what they led to are in docs/benchmarks.md.

Every module but ``harness``, ``choice``, ``hard_scenes`` and ``scale`` is a benchmark script; run one from the
repository root, with clutter-gym and its ``bench`` extra installed (``python3 tasks.py bench`` runs
``speed_vs_error``, which gathers the speed-against-error sections of the others into docs/speed-vs-error.md)::

    python -m benchmarks.throughput            # --help lists a benchmark's options
    python -m benchmarks.collision_fidelity --quick

``harness`` holds what the timing scripts share (random-walk actions, step timers, alternating rounds, table
headers); ``choice`` the report's rows, Pareto fronts and plots; ``hard_scenes`` and ``scale`` the scenes and runs
of tests/hard_cases/ that ``hard_cases`` prints (every hard case's error figure beside its steps/s); ``peers``
other projects' envs rebuilt here so that they can be timed side by side.
"""
