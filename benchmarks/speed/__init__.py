"""Speed: steps/s and where a step's time goes, measured in one process against the raw pybullet work the step
needs, against a peer, or against the other settings of a choice.

``throughput`` (ClutterNav-v1 against its floor and PandaReach-v3), ``vec_throughput`` (vector envs and the
training loop), ``fly_throughput`` (ClutterFly-v1 against gym-pybullet-drones' HoverAviary; its floor in
``fly_floor``), ``camera_throughput`` (the RGB-D env against the drones' camera env), ``physics_rate`` (physics
rate and solver iterations against trajectory error), ``noise_cost`` (what each noise profile costs), ``aero_cost``
(ClutterFly-v1's aerodynamic effects against trajectory error) and ``versus_commit`` (this working tree against an
earlier commit).
"""
