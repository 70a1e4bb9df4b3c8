"""URDFs and meshes written for clutter-gym, shipped inside the wheel as package data."""

from pathlib import Path

ASSET_DIR = Path(__file__).resolve().parent


def asset_path(relative: str) -> Path:
    """Absolute path of an asset, e.g. ``asset_path("robots/diffbot.urdf")``.

    Raises:
        FileNotFoundError: the asset does not exist (the message names the path looked up).
    """
    path = ASSET_DIR / relative
    if not path.is_file():
        raise FileNotFoundError(f"clutter-gym asset not found: {path}")
    return path
