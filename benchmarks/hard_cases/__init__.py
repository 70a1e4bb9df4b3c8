"""Hard cases (docs/hard-cases.md): ``catalogue`` measures a short version of every row with a figure, in one table;
the others are the longer runs behind single rows: ``tunneling``, ``stacking`` (stacks and mass ratios),
``large_scenes``, ``memory`` (resident memory over many resets) and ``long_runs`` (random steps, resets and
make/close cycles by the hundred thousand).
"""
