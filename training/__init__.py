"""Policies and training tooling for clutter-gym envs (installed as ``clutter_gym.training``).

``load(run_dir)`` gives a trained run's :class:`Agent`. The scripted baselines, the configs and the ``*Train-v1``
envs need only the envs' own dependencies; ``load`` and ``Agent`` need the ``[train]`` extra (stable-baselines3 and
torch), which is imported when one of them is first used, so that a bare ``pip install clutter-gym`` can run the
envs, their scripted policies and the command line's ``demo`` and ``profiles``.
"""

from __future__ import annotations

import re
from importlib import metadata
from typing import TYPE_CHECKING, Any

from gymnasium.error import DependencyNotInstalled

if TYPE_CHECKING:
    from clutter_gym.training.agent import Agent, load

__all__ = ["Agent", "load", "require_train_extra"]

INSTALL_TRAIN = "pip install 'clutter-gym[train]'"


def missing_train_packages() -> list[str]:
    """The distributions of the ``[train]`` extra (as the installed package's metadata lists them) that are not
    installed; empty for a source tree that was never installed, which has no such list."""
    try:
        requires = metadata.requires("clutter-gym") or []
    except metadata.PackageNotFoundError:
        return []
    missing = []
    for line in requires:
        requirement, _, marker = line.partition(";")
        if re.search(r"""extra\s*==\s*["']train["']""", marker):
            name = re.match(r"[A-Za-z0-9._-]+", requirement.strip()).group()  # type: ignore[union-attr]
            try:
                metadata.distribution(name)
            except metadata.PackageNotFoundError:
                missing.append(name)
    return missing


def require_train_extra(what: str) -> None:
    """Raise Gymnasium's ``DependencyNotInstalled``, naming the install command, when the ``[train]`` extra is
    missing; ``what`` (``"this command"``, ``"clutter_gym.training.load"``) is what needs it.

    Raises:
        DependencyNotInstalled: a distribution of the extra is not installed.
    """
    missing = missing_train_packages()
    if missing:
        raise DependencyNotInstalled(f"{what} needs the training extra, which is not installed (missing: "
                                     f"{', '.join(missing)}): {INSTALL_TRAIN}")


def __getattr__(name: str) -> Any:
    if name in ("Agent", "load"):
        require_train_extra(f"clutter_gym.training.{name}")
        from clutter_gym.training import agent

        globals().update(Agent=agent.Agent, load=agent.load)  # found without this hook from now on
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
