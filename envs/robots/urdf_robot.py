"""The lifecycle every robot shares: its URDF loaded once as one pybullet body, hidden from the LIDAR's rays, its
links looked up by name, and its per-episode dynamics scaled from the nominal values read at load.

A robot class sets ``name``, ``base_link`` and ``urdf_path``, calls :meth:`UrdfRobot._load` and
:meth:`UrdfRobot._index_links` from its ``load``, keeps ``_nominal`` (link index -> (mass, friction, inertia
diagonal)) and says what the episode's motor strength does in :meth:`UrdfRobot._set_motor_scale`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.robots.dynamics import scale_link_dynamics
from clutter_gym.sim import Sim


class UrdfRobot:
    """Shared plumbing of the robots (see the module docstring)."""

    name: str
    base_link: str
    link_index: dict[str, int]
    link_names: tuple[str, ...]
    _sim: Sim | None = None
    _body: int = -1
    _tracked: tuple[int, ...] = ()
    _nominal: dict[int, tuple]
    _dynamics: DynamicsSample = DynamicsSample()

    @property
    def urdf_path(self) -> Path:
        raise NotImplementedError

    @property
    def body(self) -> int:
        return self._body

    def _load(self, sim: Sim, fixed_base: bool = False, merge_fixed_links: bool = False) -> int:
        """Load the URDF into ``sim`` (once per Sim), hidden from rays; a fresh episode's dynamics are nominal.

        Raises:
            ValueError: pybullet refuses the URDF (the message names the robot: a spec's URDF is loaded from its
                prepared copy in the user cache).
        """
        self._sim = sim
        try:
            self._body = sim.load_urdf("robot", self.urdf_path, fixed_base=fixed_base,
                                       merge_fixed_links=merge_fixed_links)
        except ValueError as error:
            raise ValueError(f"robot {self.name!r}: {error}") from None
        sim.rays.hide_from_rays(self._body)
        self._dynamics = DynamicsSample()
        return self._body

    def _index_links(self, tracked: Sequence[str]) -> None:
        """Look every link up by name, and the ``tracked`` ones (read every step) in their order."""
        self.link_index = self._sim.link_indices(self._body)
        self.link_names = tuple(tracked)
        self._tracked = tuple(self.link_index[name] for name in tracked)

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """This episode's masses (inertias scale with them), friction and restitution relative to the URDF's, and
        its motor strength (a no-op when nothing changed since the last episode)."""
        if sample == self._dynamics:
            return
        scale_link_dynamics(self._sim, self._body, self._nominal, sample)
        self._set_motor_scale(sample.motor_scale)
        self._dynamics = sample

    def _set_motor_scale(self, scale: float) -> None:
        raise NotImplementedError
