"""Peers: other projects' envs rebuilt here, call for call, because they cannot be installed on this machine.

``drones``: gym-pybullet-drones' ``HoverAviary(obs=RGB, act=RPM)`` step and reset as bare pybullet calls, with
its Crazyflie body (URDF and a stand-in visual mesh) in ``drone_body``; ``drones_peer`` times it alone (the
speed benchmarks time it beside ours). ``hover``: the same package's default
``HoverAviary`` (kinematic observation, RPM action), its body in ``cf2x_hover.urdf``. panda-gym's PandaReach-v3
installs with the ``bench`` extra, so the scripts make it with ``gym.make`` and it has no module here.
"""
