"""Per-episode dynamics randomisation on a loaded robot: the link part every robot's ``apply_dynamics`` shares."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.sim import Sim


def scale_link_dynamics(
    sim: Sim, body: int, nominal: Mapping[int, tuple[float, float, Sequence[float]]], sample: DynamicsSample
) -> None:
    """Set each link's mass (its inertia scaled with it) and lateral friction to ``sample``'s multiples of the
    ``nominal`` values, and its restitution to ``sample.restitution``.

    Args:
        sim: the simulator holding the robot.
        body: the robot's pybullet body id.
        nominal: (mass kg, lateral friction, inertia diagonal kg m^2) by pybullet link index, as
            :meth:`Sim.inertial_properties` read them from the URDF at load time.
        sample: this episode's dynamics.
    """
    for link, (mass, friction, inertia) in nominal.items():
        sim.actuation.set_dynamics(
            body,
            link,
            mass=mass * sample.mass_scale,
            inertia=[sample.mass_scale * i for i in inertia],
            lateral_friction=friction * sample.friction_scale,
            restitution=sample.restitution,
        )
