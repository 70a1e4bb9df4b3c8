"""The per-step pybullet work of gym-pybullet-drones' vision setting, rebuilt so it can be timed here.

gym-pybullet-drones (utiasDSL/gym-pybullet-drones) cannot be installed on this machine (it is not on the
package index and there is no network), so this file replays, call for call, the pybullet work its
vision-observation env does: ``HoverAviary(obs=ObservationType.RGB, act=ActionType.RPM)``, i.e. ``BaseAviary``
+ ``BaseRLAviary`` + ``HoverAviary`` with the defaults of the versions read. Nothing of the peer's code or text is
copied; the facts below (call arguments, rates, scene contents, constants) are what carries over.

Sources read (GitHub, utiasDSL/gym-pybullet-drones; one stored version each):

* ``gym_pybullet_drones/envs/BaseAviary.py`` at 50d1a958def27121bcf63f3cc753049fee8e71e5 (same code at
  00ca90a9d3ee4ae83f5654965c25c71481181e9d): step loop, physics, kinematics reads, camera, reset.
* ``gym_pybullet_drones/envs/BaseRLAviary.py`` and ``gym_pybullet_drones/envs/HoverAviary.py`` at
  2c2470c2043eb4cf474d9af2681c9fa10f2d0e2f: RGB observation, landmarks, RPM action, reward/termination.
* ``gym_pybullet_drones/assets/cf2x.urdf`` at 998746d9394cca7435429acd97ee4627235b4518 and
  ``gym_pybullet_drones/assets/cf2.dae`` at 71a1ad55f40194c27b0e920b133a8c64ee19c5b9: the drone body.
* ``README.md`` at 00dde8bfb1b9b0e2b20bc5c9cfef49c17c19ba80 (an early version): the published vision
  benchmark, 240 Hz physics, 48 Hz control, nearby obstacles and a background, 24 FPS 64x48 capture of RGBA,
  depth and segmentation, CPU TinyRenderer: 1.3x real time for one drone on a 2020 MacBook Pro.

Facts reproduced
----------------
Timing
  * physics at ``pyb_freq`` = 240 Hz (``setTimeStep(1/240)``), ``PYB_STEPS_PER_CTRL = pyb_freq // ctrl_freq``
    ``stepSimulation`` calls per env step, ``setRealTimeSimulation(0)``, gravity (0, 0, -9.8).
  * onboard camera at ``IMG_FRAME_PER_SEC = 24``: ``IMG_CAPTURE_FREQ = int(240 / 24) = 10`` physics steps; an
    image is taken in ``_computeObs`` when ``step_counter % 10 == 0`` (the counter counts physics steps and is
    advanced after the observation), so at reset and then every ``10 / PYB_STEPS_PER_CTRL`` env steps.
  * ``ctrl_freq`` must make 10 a multiple of ``PYB_STEPS_PER_CTRL`` (the peer prints an error and exits
    otherwise), so HoverAviary's default 30 Hz cannot run with RGB observations; allowed are 24, 48, 120 and
    240 Hz. The default here is 48 Hz (5 substeps, an image every 2nd env step), the control rate of the
    peer's published vision benchmark; ``ctrl_freq`` is a parameter.
Per physics substep (``Physics.PYB``, the default: no drag, ground effect or downwash model)
  * ``rpm = HOVER_RPM * (1 + 0.05 * action)`` (``ActionType.RPM``), ``forces = rpm**2 * KF``,
    ``torques = rpm**2 * KM``, ``z_torque = -t0 + t1 - t2 + t3``;
  * four ``applyExternalForce(drone, link i, [0, 0, f_i], [0, 0, 0], LINK_FRAME)`` (links 0..3 = prop0..3);
  * one ``applyExternalTorque(drone, link 4, [0, 0, z_torque], LINK_FRAME)`` (link 4 = center_of_mass);
  * one ``stepSimulation``.
Per env step
  * ``getBasePositionAndOrientation``, ``getEulerFromQuaternion``, ``getBaseVelocity`` once, after the substeps;
  * on image steps: ``getMatrixFromQuaternion``; ``computeViewMatrix(eye = pos + [0, 0, L], target =
    pos + R @ [1000, 0, 0], up = [0, 0, 1])``; ``computeProjectionMatrixFOV(fov=60, aspect=1.0, near=L,
    far=1000)``; ``getCameraImage(width=64, height=48, shadow=1, viewMatrix, projectionMatrix,
    flags=ER_NO_SEGMENTATION_MASK)`` with no ``renderer`` argument, so in a DIRECT client the CPU
    TinyRenderer (BaseRLAviary asks for ``segmentation=False``); the rgb/depth/seg buffers are reshaped and
    the observation is the (1, 48, 64, 4) rgb array as float32;
  * HoverAviary's reward (``max(0, 2 - |target - pos|**4)``), termination (``|target - pos| < 1e-4``) and
    truncation (``|x| or |y| > 1.5``, ``z > 2``, ``|roll| or |pitch| > 0.4``, or more than 8 s), from the
    20-value state vector, as numpy work.
Scene, loaded on every reset after ``resetSimulation``
  * ``plane.urdf``; the drone; BaseRLAviary's four RGB landmarks from pybullet_data: ``block.urdf`` at
    (1, 0, .1), ``cube_small.urdf`` at (0, 1, .1), ``duck_vhacd.urdf`` at (-1, 0, .1), ``teddy_vhacd.urdf`` at
    (0, -1, .1) (all dynamic, they drop onto the plane). ``scene="vision_aviary"`` instead loads BaseAviary's
    own obstacles (``samurai.urdf``, ``duck_vhacd.urdf`` at (-.5, -.5, .05), ``cube_no_rotation.urdf`` at
    (-.5, -2.5, .5), ``sphere2.urdf`` at (0, 2, .5)), what an aviary built with ``obstacles=True`` outside
    the RL classes gets (VisionAviary, the published benchmark's "obstacles and background"); VisionAviary
    calls ``_getDroneImages`` with its default ``segmentation=True``, so that scene asks for the mask.
The drone (cf2x.urdf; its links, mass, inertia and mesh in :mod:`benchmarks.peers.drone_body`)
  * constants: arm L = 0.0397, KF = 3.16e-10, KM = 7.94e-12, g = 9.8 (the RPM action is not clipped, so
    the thrust-to-weight ratio and MAX_RPM play no part).

What could not be reproduced, and the stand-ins
------------------------------------------------
* The Crazyflie visual mesh ``cf2.dae``: a generated stand-in of about the same triangle count and file size
  (:mod:`benchmarks.peers.drone_body` says how it was sized and what that costs).
* The control rate of "the" vision setting is not fixed by the peer (see Timing): ``ctrl_freq`` changes how
  many images fall on one env step (1, 1/2, 1/5 or 1/10), and with it steps/s by a factor of several.
* The peer's Python around the calls (gymnasium's passive checker, the action deque, the info dict) is
  reproduced only where it is numpy work of the same kind; the deque and the wrappers are not.

``python -m benchmarks.peers.drones_peer`` times this workload alone (figures measured here in its docstring);
``python -m benchmarks.speed.camera_throughput`` times it against ClutterNav-v1 with a camera.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from dataclasses import dataclass

import numpy as np
import pybullet_data

from benchmarks.harness import pb
from benchmarks.peers.drone_body import COLLISION_H, COLLISION_Z_OFFSET, DRONE_TRIANGLES, MASS, write_drone
from clutter_gym.util.quiet import quiet_c_output

# Crazyflie 2.x constants from cf2x.urdf / BaseAviary.
G = 9.8
ARM = 0.0397  # L: the camera sits L above the centre and L is the near plane
KF = 3.16e-10
KM = 7.94e-12
HOVER_RPM = math.sqrt(G * MASS / (4 * KF))
START = (0.0, 0.0, COLLISION_H / 2 - COLLISION_Z_OFFSET + 0.1)
TARGET = np.array([0.0, 0.0, 1.0])
EPISODE_LEN_SEC = 8

IMG_RES = (64, 48)
IMG_FRAME_PER_SEC = 24

RL_LANDMARKS = (
    ("block.urdf", (1.0, 0.0, 0.1)),
    ("cube_small.urdf", (0.0, 1.0, 0.1)),
    ("duck_vhacd.urdf", (-1.0, 0.0, 0.1)),
    ("teddy_vhacd.urdf", (0.0, -1.0, 0.1)),
)
VISION_AVIARY_OBSTACLES = (
    ("samurai.urdf", None),
    ("duck_vhacd.urdf", (-0.5, -0.5, 0.05)),
    ("cube_no_rotation.urdf", (-0.5, -2.5, 0.5)),
    ("sphere2.urdf", (0.0, 2.0, 0.5)),
)


def apply_rotor_forces(cid: int, drone: int, rpm: np.ndarray) -> None:
    """gym-pybullet-drones' ``BaseAviary._physics`` for one drone and one physics tick: each rotor's thrust
    ``KF * rpm^2`` on links 0-3 and the summed drag torque on link 4 (the centre-of-mass link), link frames."""
    forces = rpm ** 2 * KF
    torques = rpm ** 2 * KM
    z_torque = -torques[0] + torques[1] - torques[2] + torques[3]
    for i in range(4):
        pb.applyExternalForce(drone, i, forceObj=[0, 0, forces[i]], posObj=[0, 0, 0], flags=pb.LINK_FRAME,
                              physicsClientId=cid)
    pb.applyExternalTorque(drone, 4, torqueObj=[0, 0, z_torque], flags=pb.LINK_FRAME, physicsClientId=cid)


@dataclass(frozen=True)
class DroneCameraConfig:
    pyb_freq: int = 240
    ctrl_freq: int = 48
    scene: str = "rl"  # "rl": BaseRLAviary's RGB landmarks; "vision_aviary": BaseAviary's samurai scene
    segmentation: bool | None = None  # None: what the scene's env asks for (False for rl, True for vision_aviary)
    drone_triangles: int = DRONE_TRIANGLES


class DroneCameraWorkload:
    """gym-pybullet-drones' HoverAviary(obs=RGB, act=RPM) step and reset, as bare pybullet calls."""

    def __init__(self, config: DroneCameraConfig = DroneCameraConfig()) -> None:
        if config.pyb_freq % config.ctrl_freq:
            raise ValueError("pyb_freq must be a multiple of ctrl_freq")
        self.config = config
        self.substeps = config.pyb_freq // config.ctrl_freq
        self.img_capture_freq = int(config.pyb_freq / IMG_FRAME_PER_SEC)
        if self.img_capture_freq % self.substeps:
            raise ValueError(f"ctrl_freq {config.ctrl_freq} Hz is incompatible with the 24 FPS camera "
                             "(the peer exits here): use 24, 48, 120 or 240 Hz")
        if config.scene not in ("rl", "vision_aviary"):
            raise ValueError("scene is 'rl' or 'vision_aviary'")
        seg = config.segmentation if config.segmentation is not None else config.scene == "vision_aviary"
        self.seg_flag = pb.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX if seg else pb.ER_NO_SEGMENTATION_MASK
        self._dir = tempfile.mkdtemp(prefix="peer_drones_")
        self.urdf, self.drone_triangles = write_drone(self._dir, config.drone_triangles)
        with quiet_c_output():
            self.cid = pb.connect(pb.DIRECT)
        self.rgb = np.zeros((1, IMG_RES[1], IMG_RES[0], 4))
        self.dep = np.ones((1, IMG_RES[1], IMG_RES[0]))
        self.seg = np.zeros((1, IMG_RES[1], IMG_RES[0]))
        self.last_clipped_action = np.zeros((1, 4))
        self.images = 0

    def close(self) -> None:
        if self.cid is not None:
            pb.disconnect(physicsClientId=self.cid)
            self.cid = None
        shutil.rmtree(self._dir, ignore_errors=True)

    # -- reset: resetSimulation + BaseAviary._housekeeping + kinematics + first observation ----------------

    def reset(self) -> tuple[np.ndarray, dict]:
        cid = self.cid
        with quiet_c_output():
            pb.resetSimulation(physicsClientId=cid)
            self.step_counter = 0
            self.last_clipped_action = np.zeros((1, 4))
            pb.setGravity(0, 0, -G, physicsClientId=cid)
            pb.setRealTimeSimulation(0, physicsClientId=cid)
            pb.setTimeStep(1.0 / self.config.pyb_freq, physicsClientId=cid)
            pb.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
            pb.loadURDF("plane.urdf", physicsClientId=cid)
            self.drone = pb.loadURDF(self.urdf, START, pb.getQuaternionFromEuler([0, 0, 0]),
                                     flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
            if self.config.scene == "rl":
                for name, pos in RL_LANDMARKS:
                    pb.loadURDF(name, pos, pb.getQuaternionFromEuler([0, 0, 0]), physicsClientId=cid)
            else:
                for name, pos in VISION_AVIARY_OBSTACLES:
                    if pos is None:
                        pb.loadURDF(name, physicsClientId=cid)
                    else:
                        pb.loadURDF(name, pos, pb.getQuaternionFromEuler([0, 0, 0]), physicsClientId=cid)
        self._read_kinematics()
        return self._observation(), {"answer": 42}

    # -- step: BaseAviary.step with Physics.PYB, BaseRLAviary RPM action and RGB observation ----------------

    def step(self, action):
        cid, drone = self.cid, self.drone
        action = np.asarray(action, dtype=np.float64).reshape(1, 4)
        rpm = HOVER_RPM * (1 + 0.05 * action)  # ActionType.RPM
        for _ in range(self.substeps):
            apply_rotor_forces(cid, drone, rpm[0])
            pb.stepSimulation(physicsClientId=cid)
            self.last_clipped_action = rpm
        self._read_kinematics()
        obs = self._observation()
        # HoverAviary rebuilds the 20-value state vector in each of reward, terminated and truncated.
        reward = max(0.0, 2 - np.linalg.norm(TARGET - self._state()[0:3]) ** 4)
        terminated = bool(np.linalg.norm(TARGET - self._state()[0:3]) < 0.0001)
        s = self._state()
        truncated = bool(abs(s[0]) > 1.5 or abs(s[1]) > 1.5 or s[2] > 2.0 or abs(s[7]) > 0.4 or abs(s[8]) > 0.4
                         or self.step_counter / self.config.pyb_freq > EPISODE_LEN_SEC)
        self.step_counter += self.substeps
        return obs, reward, terminated, truncated, {"answer": 42}

    # -- helpers -------------------------------------------------------------------------------------------

    def _read_kinematics(self) -> None:
        pos, quat = pb.getBasePositionAndOrientation(self.drone, physicsClientId=self.cid)
        self.pos, self.quat = np.array(pos), np.array(quat)
        self.rpy = np.array(pb.getEulerFromQuaternion(quat))
        vel, ang_v = pb.getBaseVelocity(self.drone, physicsClientId=self.cid)
        self.vel, self.ang_v = np.array(vel), np.array(ang_v)

    def _state(self) -> np.ndarray:
        return np.hstack([self.pos, self.quat, self.rpy, self.vel, self.ang_v,
                          self.last_clipped_action[0]]).reshape(20)

    def _observation(self) -> np.ndarray:
        if self.step_counter % self.img_capture_freq == 0:
            self.rgb[0], self.dep[0], self.seg[0] = self._drone_image()
            self.images += 1
        return np.array([self.rgb[0]]).astype("float32")

    def _drone_image(self):
        rot = np.array(pb.getMatrixFromQuaternion(self.quat)).reshape(3, 3)
        target = rot @ np.array([1000, 0, 0]) + self.pos
        view = pb.computeViewMatrix(cameraEyePosition=self.pos + np.array([0, 0, ARM]), cameraTargetPosition=target,
                                    cameraUpVector=[0, 0, 1], physicsClientId=self.cid)
        proj = pb.computeProjectionMatrixFOV(fov=60.0, aspect=1.0, nearVal=ARM, farVal=1000.0)
        w, h, rgb, dep, seg = pb.getCameraImage(width=IMG_RES[0], height=IMG_RES[1], shadow=1, viewMatrix=view,
                                                projectionMatrix=proj, flags=self.seg_flag,
                                                physicsClientId=self.cid)
        return np.reshape(rgb, (h, w, 4)), np.reshape(dep, (h, w)), np.reshape(seg, (h, w))


def make_drone_camera_workload(**overrides) -> DroneCameraWorkload:
    """The peer's vision-env workload; keyword arguments override ``DroneCameraConfig`` fields."""
    return DroneCameraWorkload(DroneCameraConfig(**overrides))
