"""A fixed-base arm moved by its reduced model (:mod:`clutter_gym.dynamics.arm_model`) wherever its step touches
nothing, and by full physics otherwise.

Each step's joint motion is first computed by the model from the arm's state. A point of link ``k`` moves by at most
``sum_j turned_j * r_jk`` over the step, ``turned_j`` the angle joint ``j`` turned through and ``r_jk`` the distance
from joint ``j`` to the farthest point of link ``k``'s collision shapes, for the joints link ``k`` moves with; the
distances themselves change while the arm moves, by at most twice the largest such move, which the bound adds
(:meth:`ReducedArm._moves`). While every link's bound stays below its clearance FCL measured before the step, less the
contact tolerance, nothing can have touched: pybullet is not stepped, and its joints are set to the model's positions
and velocities (so its forward kinematics, a camera and the next full step see the model's arm). Otherwise the step
runs under full physics. An episode whose scene has a movable obstacle runs under full physics throughout.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from clutter_gym.datatypes import CollisionReport, DynamicsSample, Obstacle, RobotState
from clutter_gym.dynamics.arm_model import arm_ticks
from clutter_gym.dynamics.base import Dynamics, FullPhysics
from clutter_gym.robots.arm import Arm
from clutter_gym.sim import Sim


class ReducedArm(Dynamics):
    """See the module docstring.

    Args:
        radii: per moving link with collision geometry, in the order of the collision report's ``link_clearance``
            (by name), metres: the farthest point of its shapes (padding included) from its frame's origin.
        contact_tolerance: metres, the env's: a clearance below it is a contact.

    Attributes:
        full: whether the last step ran under full physics (True at an episode's start).
        reduced_steps, full_steps: the steps run under each since the env was made.
    """

    def __init__(self, sim: Sim, robot: Arm, radii: Mapping[str, float], contact_tolerance: float,
                 reason: str = "") -> None:
        self.sim, self.robot, self.tolerance, self.reason = sim, robot, contact_tolerance, reason
        self.radii = dict(radii)
        self.physics = FullPhysics(sim, robot, reason)
        self.full, self._episode_full = True, True
        self.reduced_steps = self.full_steps = 0
        self._clearance = np.zeros(len(self.radii))
        self._last: RobotState | None = None

    def apply_dynamics(self, sample: DynamicsSample) -> None:
        """The arm's links take the sample (for the steps under full physics); the model's ideal motors have no force
        limit for motor strength or mass to change."""
        self.physics.apply_dynamics(sample)

    def episode_start(self, obstacles: Sequence[Obstacle]) -> dict[str, object]:
        robot = self.robot
        self._rows = [robot.link_names.index(name) for name in self.radii]  # clearance order -> state rows
        self._radius = np.array(list(self.radii.values()))
        joints, links = np.array(robot.arm_joints), np.array([robot.link_index[name] for name in self.radii])
        self._beyond = links[None, :] >= joints[:, None]  # (joint, link): the link moves with the joint
        # each joint's axis passes through its child link's origin: the state's row of that link, where it is tracked
        tracked = {robot.link_index[name]: row for row, name in enumerate(robot.link_names)}
        self._origin_rows = [tracked[j] for j in joints] if all(j in tracked for j in joints) else None
        self._episode_full = any(o.movable for o in obstacles)
        self.full = True  # pybullet holds the arm at its start: its contacts are the reset's
        self._clearance = np.zeros(len(self.radii))
        if self._episode_full:
            return {"model": "physics", "reason": "a movable obstacle in the scene: full physics for the episode"}
        return {"model": "reduced", "reason": self.reason}

    def advance(self, command: np.ndarray, substeps: int) -> None:
        robot, sim = self.robot, self.sim
        robot.apply_action(command)
        if not self._episode_full and self._clearance.min() > self.tolerance and self._last is not None:
            q, v = self._last.joint_position.copy(), self._last.joint_velocity.copy()
            target, velocity = robot.held_command()
            turned = arm_ticks(q, v, target, velocity, 1.0 / sim.physics_hz, substeps)
            if np.all(self._moves(turned) + self.tolerance < self._clearance):
                sim.actuation.reset_joints(robot.body, robot.arm_joints, q.tolist(), v.tolist())
                self.reduced_steps += 1
                self.full = False
                return
        self.full_steps += 1
        self.full = True
        self.physics.run(substeps)

    def _moves(self, turned: np.ndarray) -> np.ndarray:
        """Metres, per link: how far any point of its collision shapes can have moved while each joint turned through
        ``turned`` (rad), from the arm's last state."""
        total = float(turned.sum())
        if total >= 0.5:
            return np.full(len(self._radius), np.inf)
        last = self._last
        assert last is not None
        if self._origin_rows is not None:
            origins = last.links.position[self._origin_rows]
        else:
            origins = self.sim.link_states(self.robot.body, self.robot.arm_joints).position
        reach = np.linalg.norm(last.links.position[self._rows][None, :, :] - origins[:, None, :], axis=2)
        moves = turned @ np.where(self._beyond, reach + self._radius, 0.0)
        # while the arm moves, a point's distance from a joint grows by at most twice the largest move
        largest = moves.max() / (1.0 - 2.0 * total)
        return moves + 2.0 * total * largest

    def state(self) -> RobotState:
        self._last = self.robot.state()
        return self._last

    def contacts(self) -> list[tuple[int, float]]:
        # a reduced step moved less than the clearance it began with: pybullet, not stepped, has no new contact
        return self.physics.contacts() if self.full else []

    def checked(self, report: CollisionReport) -> None:
        links = report.link_clearance
        self._clearance = links if links is not None else np.full(len(self.radii), report.min_clearance)
