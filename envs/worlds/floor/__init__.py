"""The floor world of ClutterNav-v1: a walled square arena with seeded clutter, its clearance grid and the path
distance around the clutter."""
