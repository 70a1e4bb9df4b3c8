"""Speed and accuracy benchmarks of clutter-gym; results and what they led to are in docs/benchmarks.md.

Every module but ``harness`` is a benchmark script; run one from the repository root, with clutter-gym and its
``bench`` extra installed (``python3 tasks.py bench`` runs ``throughput``)::

    python -m benchmarks.throughput            # --help lists a benchmark's options
    python -m benchmarks.collision_fidelity --quick

``harness`` holds what the timing scripts share (random-walk actions, step timers, alternating rounds, table
headers); ``peers`` holds other projects' envs rebuilt here so that they can be timed side by side.
"""
