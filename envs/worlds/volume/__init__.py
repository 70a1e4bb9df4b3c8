"""The volume of ClutterFly-v1: a walled box of air with seeded 3D clutter, its clearance grid and the path distance
through it."""
