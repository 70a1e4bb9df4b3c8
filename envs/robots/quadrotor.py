"""The quadrotor (assets/robots/quadrotor.urdf), a Crazyflie-2.x-sized X-configuration nano quadrotor: its constants
and its :class:`MultirotorModel`. The class that flies it, and any other multirotor, is ``robots/multirotor.py``'s
``Multirotor``. Coefficients and their sources: docs/quadrotor.md.
"""

from __future__ import annotations

from clutter_gym.assets import asset_path
from clutter_gym.robots.multirotor import Multirotor, MultirotorConfig
from clutter_gym.robots.multirotor_model import IMU_LINK, SENSOR_LINK, MultirotorModel

ROTOR_LINKS = ("rotor_1", "rotor_2", "rotor_3", "rotor_4")
#: Spin of each rotor of ``ROTOR_LINKS``: +1 counter-clockwise seen from above. Diagonal rotors turn alike, so equal
#: speeds cancel their drag torques; rotor_1 (front right) turns counter-clockwise.
ROTOR_SPIN = (1.0, -1.0, 1.0, -1.0)
#: Links whose states are read every control step: every link with collision geometry, the IMU and the sensor mount.
TRACKED_LINKS = ("battery", "arm_1", "arm_2", "arm_3", "arm_4", *ROTOR_LINKS, IMU_LINK, SENSOR_LINK)
RING_RADIUS = 0.066  # metres from the base origin to a propeller tip, as in the URDF


def quadrotor_model() -> MultirotorModel:
    """The quadrotor every ClutterFly result so far was measured with."""
    return MultirotorModel(
        name="quadrotor", urdf=asset_path("robots/quadrotor.urdf"), base_link="base_link", rotor_links=ROTOR_LINKS,
        spin=ROTOR_SPIN, tracked_links=TRACKED_LINKS, thrust_coefficient=2.8816e-8, torque_coefficient=1.7187e-10,
        max_rotor_speed=2272.7, min_rotor_speed=0.0, motor_time_constant=0.05, drag_xy=9.1785e-7, drag_z=10.311e-7,
        rotor_radius=0.0231348, focus_radius=RING_RADIUS,
    )


#: The quadrotor's control settings are any multirotor's.
QuadrotorConfig = MultirotorConfig


class Quadrotor(Multirotor):
    """The quadrotor, flown as every multirotor is (``robots/multirotor.py``)."""

    def __init__(self, config: MultirotorConfig | None = None) -> None:
        super().__init__(quadrotor_model(), config)
