"""What a robot spec names on disk besides its URDF: the robot's ``name``, which becomes the file name of the prepared
copy in the cache, and the ``package_roots`` it grants its URDF's ``package://`` meshes.

A spec may come from someone else (a run folder's config.yaml carries one), so both are read as untrusted: the name
must be a plain file name, and a granted root must be an existing folder named by a plain package name. Meshes are
read nowhere else than the URDF's folder and these roots (:mod:`clutter_gym.util.mesh_files`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from clutter_gym.util.checks import check_file_name, short_repr

#: keys every kind of spec takes besides its own
SHARED_KEYS = ("package_roots",)


def spec_name(spec: Mapping[str, object], where: str, source: Path) -> str:
    """The spec's ``name`` when it is a plain file name; without one, the URDF's file name made plain (characters
    other than letters, digits, ``.``, ``_`` and ``-`` become ``_``, at most 64 of them).

    Raises:
        ValueError: ``name`` is not a plain file name (:func:`~clutter_gym.util.checks.check_file_name`).
    """
    if "name" in spec:
        return check_file_name(f"{where}: name", spec["name"])
    return re.sub(r"[^A-Za-z0-9._-]", "_", source.stem).lstrip(".")[:64] or "robot"


def spec_package_roots(spec: Mapping[str, object], where: str, folder: Path | None) -> dict[str, Path]:
    """The spec's ``package_roots`` (``{package: folder}``, each folder relative to ``folder``, the spec file's,
    unless absolute) as absolute paths.

    Raises:
        ValueError: not a mapping, a package name that is not a plain name, or a root that is not a folder.
    """
    roots = spec.get("package_roots") or {}
    if not isinstance(roots, Mapping):
        raise ValueError(f"{where}: package_roots must be a mapping of package names to folders, got "
                         f"{short_repr(roots)}")
    granted = {}
    for package, root in roots.items():
        check_file_name(f"{where}: a package name in package_roots", package)
        path = Path(root).expanduser() if isinstance(root, str) else None
        if path is not None and not path.is_absolute() and folder is not None:
            path = folder / path
        if path is None or not path.is_dir():
            raise ValueError(f"{where}: package_roots.{package} must be a folder, got {short_repr(root)}")
        granted[package] = path.resolve()
    return granted
