"""Helpers with no knowledge of envs, robots or tasks: atomic file writes (``atomic``), silencing C-level output
(``quiet``), episode videos (``video``), numpy-built meshes (``meshes``), rigid transforms on numpy arrays
(``transforms``), argument checks (``checks``), view culling (``view_culling``), the user cache (``cache_dir``),
YAML read with bounds (``safe_yaml``) and the mesh files a URDF names, found only where allowed (``mesh_files``).
They import nothing from clutter_gym outside this folder, so any part of the package can use them.
"""
