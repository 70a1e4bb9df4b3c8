"""Fidelity: how far an answer is from the exact one, and what being exact costs.

``collision_fidelity`` (each collision level's query time against its clearance error; FCL against pybullet),
``fcl_accuracy`` (FCL's clearance against closed forms), ``contact_agreement`` (FCL and pybullet on contact),
``coarse_self_collision`` (the coarse levels' self-collision verdicts), ``lidar_resolution`` and ``cylinder_rays``
(LIDAR ray counts and ray casters), ``camera_resolution`` and ``camera_renderer`` (camera image sizes and depth
renderers).
"""
