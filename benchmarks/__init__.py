"""Speed and accuracy benchmarks of clutter-gym; results and what they led to are in docs/benchmarks.md.

Grouped by what they measure, one subpackage each; run a benchmark from the repository root, with clutter-gym and
its ``bench`` extra installed::

    python -m benchmarks.speed.throughput               # --help lists a benchmark's options
    python -m benchmarks.fidelity.collision_fidelity --quick

* ``speed``: steps/s and where a step's time goes, against the raw pybullet work it needs and against peers;
* ``fidelity``: how far an answer is from the exact one (collision levels, FCL, contacts, LIDAR, camera);
* ``hard_cases``: the catalogue of docs/hard-cases.md and the longer runs behind its rows;
* ``learning``: trained and scripted policies against their targets;
* ``peers``: other projects' envs rebuilt here so that they can be timed side by side;
* ``pictures``: the pictures of the README and the docs.

At the top: ``speed_vs_error``, the report ``python3 tasks.py bench`` runs, which gathers the speed-against-error
sections of the others into docs/speed-vs-error.md; ``harness``, what the timing scripts share (random-walk actions,
step timers, alternating rounds, table headers); ``choice``, the report's rows, Pareto fronts and plots. The scenes
and runs that tests/hard_cases/ holds the hard cases to are ``benchmarks.hard_cases.scenes``, beside the benchmarks
that print them (not in the installed package: no user of the envs needs them).
"""
