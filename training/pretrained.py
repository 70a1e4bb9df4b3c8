"""Trained agents shipped inside the package, to start from without training: ``load("pretrained/NAME")``,
``clutter-gym eval pretrained/NAME``, ``clutter-gym demo --agent pretrained/NAME``.

Each is a slim run folder, ``clutter_gym/training/pretrained/NAME/``: the run's ``config.yaml``, its kept policy
under ``model/`` (``model.zip`` and ``vecnormalize.npz``, read as any run's: nothing is unpickled), and
``card.yaml``, which says how it was made (the command, the commit) and how well it does (its evaluation on 100
held-out layouts, and the few-episode check ``tests/training/test_pretrained.py`` holds it to).
``python -m benchmarks.learning.ship_pretrained`` writes one from a finished run.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from clutter_gym.util.safe_yaml import read_yaml

#: ``load`` and the commands read a run argument starting with this as a shipped agent's name, unless a folder of
#: that name exists where they run.
PREFIX = "pretrained/"
CARD_FILE = "card.yaml"


def pretrained_root() -> Path:
    """The folder of the shipped agents."""
    return Path(str(resources.files("clutter_gym.training").joinpath("pretrained")))


def pretrained_names() -> list[str]:
    """The shipped agents' names, sorted."""
    root = pretrained_root()
    return sorted(p.name for p in root.iterdir() if (p / CARD_FILE).is_file()) if root.is_dir() else []


def pretrained_folder(name: str) -> Path:
    """The run folder of the shipped agent ``name`` (with or without the ``pretrained/`` prefix).

    Raises:
        FileNotFoundError: no shipped agent has that name; the message lists those that do.
    """
    name = name.removeprefix(PREFIX)
    if name not in pretrained_names():
        raise FileNotFoundError(f"no shipped agent is named {name!r}; the shipped agents: "
                                f"{', '.join(PREFIX + n for n in pretrained_names()) or 'none'}")
    return pretrained_root() / name


def resolve_run(run_dir: str | Path) -> Path:
    """``run_dir`` as a folder: a shipped agent's for ``pretrained/NAME`` (unless such a folder exists here)."""
    if str(run_dir).startswith(PREFIX) and not Path(run_dir).exists():
        return pretrained_folder(str(run_dir))
    return Path(run_dir)


def card(name: str) -> dict[str, Any]:
    """A shipped agent's card: ``command``, ``commit``, ``evaluation`` (``episodes``, ``seed``, ``success``,
    ``collision``) and ``check`` (``episodes``, ``min_success``)."""
    return read_yaml(pretrained_folder(name) / CARD_FILE)
