"""Reading URDFs: what the reader refuses (``checks``), the collision and visual elements with their meshes
(``geometry``), and the kinematic tree (``kinematics``). Plain XML and numpy, and trimesh when a mesh is read: no
physics or collision engine is loaded here, so robot models read their URDFs without FCL or pybullet
(docs/architecture.md, "Rules")."""
