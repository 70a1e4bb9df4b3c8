"""The table world of ClutterReach-v1: a table in front of a fixed arm, crowded with boxes, cylinders and a shelf."""
