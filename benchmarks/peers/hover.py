"""gym-pybullet-drones' HoverAviary with kinematic observations and RPM actions, rebuilt so it can be timed here.

gym-pybullet-drones (utiasDSL/gym-pybullet-drones) is not installable on this machine, so this module performs the
same pybullet calls and the same kind of numpy work per step and per reset as ``HoverAviary()`` in its default
configuration: ``obs=ObservationType.KIN``, ``act=ActionType.RPM``, ``physics=Physics.PYB``, ``pyb_freq=240``,
``ctrl_freq=30``, one CF2X drone, no GUI, no recording. Nothing of the peer's code or text is copied; what carries
over are the facts below, read from these upstream files at commit 90b178a (2024):
``gym_pybullet_drones/envs/BaseAviary.py`` (step loop, ``_physics``, kinematics reads, housekeeping, reset),
``gym_pybullet_drones/envs/BaseRLAviary.py`` (action buffer, RPM action, KIN observation),
``gym_pybullet_drones/envs/HoverAviary.py`` (target, reward, termination, truncation, defaults) and
``gym_pybullet_drones/assets/cf2x.urdf`` (the body, see ``cf2x_hover.urdf`` next to this file).

Facts reproduced
----------------
Timing: 240 Hz physics, 30 Hz control, so ``PYB_STEPS_PER_CTRL`` = 8 ``stepSimulation`` calls per env step.
Action: a (1, 4) array in [-1, 1]; ``rpm = HOVER_RPM * (1 + 0.05 * a)`` with ``HOVER_RPM = sqrt(g m / 4 kf)``,
  g = 9.8, m = 0.027, kf = 3.16e-10, km = 7.94e-12; not clipped. Before that the action is appended to a deque of
  ``ctrl_freq // 2`` = 15 actions (filled with zeros at construction and never cleared on reset).
Per physics tick (``Physics.PYB``): forces ``rpm**2 kf`` and torques ``rpm**2 km`` are recomputed, then four
  ``applyExternalForce(drone, i, [0, 0, f_i], [0, 0, 0], LINK_FRAME)`` on links 0..3, one
  ``applyExternalTorque(drone, 4, [0, 0, -t0 + t1 - t2 + t3], LINK_FRAME)`` and one ``stepSimulation``. With
  ``Physics.PYB`` BaseAviary reads no kinematic state between ticks: its per-tick
  ``_updateAndStoreKinematicInformation`` runs only for the DYN, drag, ground-effect and downwash physics, so
  there is none here either.
After the ticks: ``getBasePositionAndOrientation``, ``getEulerFromQuaternion`` and ``getBaseVelocity`` (the one
  kinematics read), then the observation: the 20-value state vector (position, quaternion, roll-pitch-yaw,
  velocity, angular velocity, last RPMs) cut to 12 values (position, rpy, velocity, angular velocity) as float32,
  with the 15 buffered actions stacked after it one ``hstack`` at a time: shape (1, 72).
Reward ``max(0, 2 - |target - pos|**4)``, terminated when ``|target - pos| < 1e-4``, truncated when ``|x|`` or
  ``|y|`` > 1.5, ``z`` > 2, ``|roll|`` or ``|pitch|`` > 0.4, or the physics step counter over 240 Hz exceeds
  8 s; target (0, 0, 1). Each of reward, terminated and truncated rebuilds the state vector, as upstream does.
  The info dict is ``{"answer": 42}``; the step counter advances by 8 after these.
Reset: ``resetSimulation``, then ``setGravity``, ``setRealTimeSimulation(0)``, ``setTimeStep(1/240)``,
  ``setAdditionalSearchPath``, ``loadURDF("plane.urdf")``, ``getQuaternionFromEuler``, ``loadURDF`` of the drone
  at (0, 0, 0.1125) with ``URDF_USE_INERTIA_FROM_FILE`` (BaseRLAviary asks for obstacles, but its
  ``_addObstacles`` loads landmarks only for RGB observations: none here), then the kinematics read and the
  first observation.

pybullet calls (counted from the upstream step and reset as read; ``count_pybullet_calls`` counts this module's)
-----------------------------------------------------------------------------------------------------------------
Per env step: 8 x (4 ``applyExternalForce`` + 1 ``applyExternalTorque`` + 1 ``stepSimulation``) + 3 kinematics
reads = 51, the same 51 calls in the same order here (``CALLS_PER_STEP``). Per reset: 11 (``CALLS_PER_RESET``).

``python -m benchmarks.peers.hover`` prints these facts as measured on the rebuild: the observation and info, the
newest action's place in the observation, the pybullet calls per step and per reset, and when a hover and a roll
command are truncated.

What could not be reproduced, and the stand-ins
-----------------------------------------------
* The drone's visual mesh ``cf2.dae``: pybullet parses a URDF's visual meshes even in a DIRECT client, so the
  mesh is part of every reset's cost (about 15 ms of a 17 ms reset here; without a mesh the reset takes about
  2 ms). The stand-in is ``benchmarks.peers.drone_body``'s generated COLLADA file of about the same triangle count
  and size; ``visual_mesh=False`` drops it, to show how much of the peer's figure the reset's mesh parse is.
* Upstream's env is a ``gymnasium.Env`` built directly (its training script wraps it in stable-baselines3's
  ``Monitor``, not ``gym.make``'s checkers), so no wrapper is added here; ClutterFly-v1 is timed through
  ``gym.make`` with its wrappers (about 11 us a step).
* Upstream's Python around the calls (``if`` chains on GUI, recording and physics enums; the per-drone loops of
  one drone) is reproduced as the same numpy work and comparable branches, not line for line.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import tempfile
from collections import Counter, deque
from collections.abc import Callable

import gymnasium as gym
import numpy as np
import pybullet_data
from gymnasium import spaces

from benchmarks.harness import pb
from benchmarks.peers.drone_body import write_drone
from benchmarks.peers.drones import KF, apply_rotor_forces
from clutter_gym.util.quiet import quiet_c_output

URDF = os.path.join(os.path.dirname(__file__), "cf2x_hover.urdf")
G, MASS = 9.8, 0.027
HOVER_RPM = math.sqrt(G * MASS / (4 * KF))
PYB_FREQ, CTRL_FREQ = 240, 30
SUBSTEPS = PYB_FREQ // CTRL_FREQ
ACTION_BUFFER_SIZE = CTRL_FREQ // 2
START = np.array([[0.0, 0.0, 0.025 / 2 - 0.0 + 0.1]])  # COLLISION_H / 2 - COLLISION_Z_OFFSET + 0.1
TARGET = np.array([0.0, 0.0, 1.0])
EPISODE_LEN_SEC = 8
KIN_SHAPE = (1, 12 + 4 * ACTION_BUFFER_SIZE)
CALLS_PER_STEP = SUBSTEPS * (4 + 1 + 1) + 3
CALLS_PER_RESET = 11
#: physics options for which BaseAviary reads the kinematic state before every tick; 'pyb' (the default) is not one
_PER_TICK_READS = ("dyn", "pyb_gnd", "pyb_drag", "pyb_dw", "pyb_gnd_drag_dw")


class HoverKinPeer(gym.Env):
    """HoverAviary(obs=KIN, act=RPM) at its defaults, as bare pybullet calls (see the module docstring).

    Args:
        visual_mesh: load the drone with the cf2.dae stand-in as its visual (as upstream loads cf2.dae); False
            loads the same body without a visual.
    """

    def __init__(self, visual_mesh: bool = True) -> None:
        self._dir = tempfile.mkdtemp(prefix="peer_hover_")
        if visual_mesh:
            write_drone(self._dir)  # cf2_like.dae, the mesh cf2x_hover.urdf names
            self.urdf = shutil.copy(URDF, self._dir)
        else:
            self.urdf = os.path.join(self._dir, "cf2x_hover_no_visual.urdf")
            with open(URDF) as f:
                text = f.read()
            start, end = text.index("<visual>"), text.index("</visual>") + len("</visual>")
            with open(self.urdf, "w") as f:
                f.write(text[:start] + text[end:])
        self.physics = "pyb"
        self.action_buffer: deque[np.ndarray] = deque(maxlen=ACTION_BUFFER_SIZE)
        self.action_space = spaces.Box(low=-1.0, high=1.0, shape=(1, 4), dtype=np.float32)
        for _ in range(ACTION_BUFFER_SIZE):
            self.action_buffer.append(np.zeros((1, 4)))
        lo, hi = -np.inf, np.inf
        low = np.hstack([np.array([[lo, lo, 0] + [lo] * 9])] + [-np.ones((1, 4))] * ACTION_BUFFER_SIZE)
        high = np.hstack([np.full((1, 12), hi)] + [np.ones((1, 4))] * ACTION_BUFFER_SIZE)
        # float32 bounds: upstream passes float64 ones and gymnasium warns about the cast, once, at construction
        self.observation_space = spaces.Box(low=low.astype(np.float32), high=high.astype(np.float32),
                                            dtype=np.float32)
        with quiet_c_output():
            self.cid = pb.connect(pb.DIRECT)
        self._load()
        self._read_kinematics()

    def close(self) -> None:
        if self.cid is not None:
            pb.disconnect(physicsClientId=self.cid)
            self.cid = None
        shutil.rmtree(self._dir, ignore_errors=True)

    # -- reset: resetSimulation, BaseAviary._housekeeping, the kinematics read, the first observation ----------

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed, options=options)
        pb.resetSimulation(physicsClientId=self.cid)
        self._load()
        self._read_kinematics()
        return self._observation(), {"answer": 42}

    def _load(self) -> None:
        cid = self.cid
        self.step_counter = 0
        self.last_clipped_action = np.zeros((1, 4))
        self.pos, self.quat, self.rpy = np.zeros((1, 3)), np.zeros((1, 4)), np.zeros((1, 3))
        self.vel, self.ang_v = np.zeros((1, 3)), np.zeros((1, 3))
        pb.setGravity(0, 0, -G, physicsClientId=cid)
        pb.setRealTimeSimulation(0, physicsClientId=cid)
        pb.setTimeStep(1.0 / PYB_FREQ, physicsClientId=cid)
        pb.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
        pb.loadURDF("plane.urdf", physicsClientId=cid)
        self.drone = pb.loadURDF(self.urdf, START[0], pb.getQuaternionFromEuler([0.0, 0.0, 0.0]),
                                 flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)

    # -- step: BaseAviary.step with Physics.PYB, BaseRLAviary's RPM action and KIN observation ------------------

    def step(self, action):
        clipped = np.reshape(self._rpm(action), (1, 4))
        cid, drone = self.cid, self.drone
        for _ in range(SUBSTEPS):
            if SUBSTEPS > 1 and self.physics in _PER_TICK_READS:
                self._read_kinematics()
            for k in range(1):  # one drone
                apply_rotor_forces(cid, drone, np.array(clipped[k, :]))
            pb.stepSimulation(physicsClientId=cid)
            self.last_clipped_action = clipped
        self._read_kinematics()
        obs = self._observation()
        reward = max(0, 2 - np.linalg.norm(TARGET - self._state()[0:3]) ** 4)
        terminated = bool(np.linalg.norm(TARGET - self._state()[0:3]) < 0.0001)
        s = self._state()
        truncated = bool(abs(s[0]) > 1.5 or abs(s[1]) > 1.5 or s[2] > 2.0 or abs(s[7]) > 0.4 or abs(s[8]) > 0.4
                         or self.step_counter / PYB_FREQ > EPISODE_LEN_SEC)
        info = {"answer": 42}
        self.step_counter += SUBSTEPS
        return obs, reward, terminated, truncated, info

    def _rpm(self, action) -> np.ndarray:
        self.action_buffer.append(action)
        rpm = np.zeros((1, 4))
        for k in range(action.shape[0]):
            rpm[k, :] = np.array(HOVER_RPM * (1 + 0.05 * action[k, :]))
        return rpm

    # -- helpers -------------------------------------------------------------------------------------------

    def _read_kinematics(self) -> None:
        self.pos[0], self.quat[0] = pb.getBasePositionAndOrientation(self.drone, physicsClientId=self.cid)
        self.rpy[0] = pb.getEulerFromQuaternion(self.quat[0])
        self.vel[0], self.ang_v[0] = pb.getBaseVelocity(self.drone, physicsClientId=self.cid)

    def _state(self) -> np.ndarray:
        return np.hstack([self.pos[0, :], self.quat[0, :], self.rpy[0, :], self.vel[0, :], self.ang_v[0, :],
                          self.last_clipped_action[0, :]]).reshape(20)

    def _observation(self) -> np.ndarray:
        obs_12 = np.zeros((1, 12))
        s = self._state()
        obs_12[0, :] = np.hstack([s[0:3], s[7:10], s[10:13], s[13:16]]).reshape(12)
        out = np.array([obs_12[0, :]]).astype("float32")
        for i in range(ACTION_BUFFER_SIZE):
            out = np.hstack([out, np.array([self.action_buffer[i][0, :]])])
        return out


def count_pybullet_calls(fn: Callable[[], object]) -> Counter:
    """The pybullet functions ``fn()`` calls, by name and count (a profile hook sees every C call)."""
    calls: Counter = Counter()

    def hook(frame, event, arg):
        if event == "c_call" and getattr(arg, "__module__", None) == "pybullet":
            calls[arg.__name__] += 1

    previous = sys.getprofile()
    sys.setprofile(hook)
    try:
        fn()
    finally:
        sys.setprofile(previous)
    return calls


def facts(peer: HoverKinPeer) -> list[str]:
    """The facts of the module docstring, measured on ``peer``, one line each."""
    obs, info = peer.reset(seed=0)
    action = np.full((1, 4), 0.5, dtype=np.float32)
    after, reward, terminated, truncated, _ = peer.step(action)
    lines = [f"observation: shape {obs.shape} (upstream's {KIN_SHAPE}), space {peer.observation_space.shape}; info "
             f"{info}",
             f"one step of {action[0].tolist()}: the newest action is the observation's last 4 values: "
             f"{np.array_equal(after[0, -4:], action[0])}; finite: {bool(np.all(np.isfinite(after)))}; reward "
             f"{reward:.4f}, terminated {terminated}, truncated {truncated}"]
    peer.reset(seed=0)
    step = count_pybullet_calls(lambda: peer.step(np.zeros((1, 4), dtype=np.float32)))
    reset = count_pybullet_calls(peer.reset)
    lines.append(f"pybullet calls per step: {sum(step.values())} (upstream's {CALLS_PER_STEP}): "
                 f"{', '.join(f'{n} {c}' for n, c in step.items())}; per reset: {sum(reset.values())} (upstream's "
                 f"{CALLS_PER_RESET})")
    for name, command in (("hover RPMs", (0.0, 0.0, 0.0, 0.0)), ("roll command", (-1.0, -1.0, 1.0, 1.0))):
        peer.reset(seed=0)
        ended = False
        for steps in range(1, 10_000):
            obs, _, terminated, truncated, _ = peer.step(np.array([command], dtype=np.float32))
            ended = ended or terminated
            if truncated:
                break
        lines.append(f"{name} {list(command)}: truncated after {steps} steps, terminated before: {ended}; z "
                     f"{obs[0, 2]:.4f} m, roll {obs[0, 3]:.3f} rad")
    return lines


def main() -> None:
    argparse.ArgumentParser(description="Print the facts the rebuilt peer reproduces, measured on it.").parse_args()
    peer = HoverKinPeer()
    try:
        print("\n".join(facts(peer)))
    finally:
        peer.close()


if __name__ == "__main__":
    main()
