"""The reduced model of a position-controlled arm that touches nothing: each joint follows its motor's command as
pybullet's position motor asks it to, integrated per physics tick in compiled code.

pybullet's ``POSITION_CONTROL`` motor is a velocity constraint: each tick it asks the joint for the velocity
``v* = kp (q_target - q) / dt + kd (v_target - v) + v`` (``kp`` 0.1 and ``kd`` 1 by default, so
``v* = v_target + 0.1 (q_target - q) / dt``), and the joint then moves by its new velocity over the tick. The model
gives every joint that velocity: an ideal motor. What it leaves out is what keeps pybullet's joints from getting it
at once: the force limit against the arm's inertia, gravity and the coupling of the joints, which the constraint
solver meets within its iterations. docs/speed-vs-error.md gives the error this costs.
"""

from __future__ import annotations

import numba
import numpy as np

#: pybullet's default gains of a position motor (setJointMotorControlArray without positionGains/velocityGains)
POSITION_GAIN, VELOCITY_GAIN = 0.1, 1.0


@numba.njit(cache=True)
def arm_ticks(q: np.ndarray, v: np.ndarray, target: np.ndarray, target_velocity: np.ndarray, dt: float,
              ticks: int) -> np.ndarray:
    """Advance the joint positions ``q`` (rad) and velocities ``v`` (rad/s) in place by ``ticks`` ticks of ``dt``
    seconds towards the motors' ``target`` and ``target_velocity``. Returns the angle each joint turned through (its
    path, rad), which bounds how far the arm's points moved."""
    travelled = np.zeros(q.shape[0])
    for _ in range(ticks):
        for j in range(q.shape[0]):
            v[j] = POSITION_GAIN * (target[j] - q[j]) / dt + VELOCITY_GAIN * (target_velocity[j] - v[j]) + v[j]
            q[j] += v[j] * dt
            travelled[j] += abs(v[j]) * dt
    return travelled
