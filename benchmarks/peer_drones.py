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
The drone (cf2x.urdf)
  * base_link: mass 0.027 kg, inertia diag(1.4e-5, 1.4e-5, 2.17e-5) (``URDF_USE_INERTIA_FROM_FILE``),
    collision cylinder r = 0.06, length 0.025; five massless fixed child links (prop0..3, center_of_mass),
    so it is a 5-link multibody; visual mesh with origin rpy (0, 0, 55); start (0, 0, 0.1125).
  * constants: arm L = 0.0397, KF = 3.16e-10, KM = 7.94e-12, g = 9.8 (the RPM action is not clipped, so
    the thrust-to-weight ratio and MAX_RPM play no part).

What could not be reproduced, and the stand-ins
------------------------------------------------
* The Crazyflie visual mesh ``cf2.dae`` (COLLADA, 530 kB) is not available here and is not copied. Its triangle
  count matters to TinyRenderer, which transforms and clips every triangle of every body in both the shadow
  pass and the colour pass. From the stored file: 37 geometries written as triangle ``polylist``s with
  positions and separately indexed normals, a 792-triangle propeller instanced 4 times, motor mounts of
  328-330 and 36 triangles, millimetre units under a 0.001-scale root node. Only part of the file was read,
  so the total is an estimate from its text density: about 8,200 triangles (roughly 7,000-9,500). The
  stand-in is a generated COLLADA file of the same form (one geometry per part, ``polylist`` with normals,
  the propeller geometry instanced 4 times, 0.001 root scale, about one position per triangle) with
  ``DRONE_TRIANGLES`` triangles laid out like cf2.dae's parts (plate, four arms, leg-like mounts, motors,
  pins, four 46 mm two-blade propellers with hubs 12.7 mm up, as the stored file places them) and a text of
  377 kB, so the rendering cost and the mesh-parsing cost of each reset are of the same size. Its shapes are
  not the real ones. Measured sensitivity: about 0.27 ms of CPU per
  image per 1,000 drone triangles (the whole drone costs about 1.9 ms of a 5.6 ms image), so the
  7,000-9,500 range moves steps/s by about 5% either way.
* The control rate of "the" vision setting is not fixed by the peer (see Timing): ``ctrl_freq`` changes how
  many images fall on one env step (1, 1/2, 1/5 or 1/10), and with it steps/s by a factor of several.
* The peer's Python around the calls (gymnasium's passive checker, the action deque, the info dict) is
  reproduced only where it is numpy work of the same kind; the deque and the wrappers are not.

Measured here (2 shared cores, pybullet 3.2.7, 2,000 random-action steps; the machine drifts by 15-20%
between runs minutes apart, so compare only figures from one run)
-----------------------------------------------------------------------------------------------------------
The default (landmark scene, 48 Hz): 356-369 steps/s counting ``step()`` alone, 277-287 steps/s with the
HoverAviary resets included (a random policy tips the drone past 0.4 rad in about 0.6 s, so about 70
resets of 22-23 ms each). Medians over interleaved blocks, per CPU second, ``step()`` alone (with resets):
landmarks at 24 Hz 183 (128), 48 Hz 364 (265), 240 Hz 1,730 (1,530); the samurai scene at 48 Hz 56 (37),
at 240 Hz 274 (220). The image is the bulk of the cost (about 5.6 ms each in the landmark scene and
35 ms in the samurai scene, against about 0.07 ms per physics substep), so steps/s follows images/step.
The ~237 steps/s quoted for the real peer on this machine lies between the 24 Hz and 48 Hz figures,
within about 20% of the 48 Hz figure with resets counted and of the samurai scene at 240 Hz.

Run ``python benchmarks/peer_drones.py`` (``--help`` for the options, ``--sweep`` for every allowed control
rate in both scenes) to print steps/s.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():  # pybullet prints its build banner on import
    import pybullet as pb
    import pybullet_data

# Crazyflie 2.x constants from cf2x.urdf / BaseAviary.
G = 9.8
MASS = 0.027
ARM = 0.0397  # L: the camera sits L above the centre and L is the near plane
KF = 3.16e-10
KM = 7.94e-12
COLLISION_H, COLLISION_R, COLLISION_Z_OFFSET = 0.025, 0.06, 0.0
HOVER_RPM = math.sqrt(G * MASS / (4 * KF))
START = (0.0, 0.0, COLLISION_H / 2 - COLLISION_Z_OFFSET + 0.1)
TARGET = np.array([0.0, 0.0, 1.0])
EPISODE_LEN_SEC = 8

IMG_RES = (64, 48)
IMG_FRAME_PER_SEC = 24
DRONE_TRIANGLES = 8200  # estimate of cf2.dae's triangle count (instances included), see the module docstring

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


# ----------------------------------------------------------------------------------------------------------
# Drone body: a URDF with cf2x's links and inertia and a generated COLLADA mesh of Crazyflie-like complexity.


def _ellipsoid(center, radii, n_lon: int, n_lat: int, yaw: float = 0.0):
    """Latitude/longitude ellipsoid: 2 * n_lon * (n_lat - 1) triangles (the pole rows are fans)."""
    th = np.linspace(0.0, math.pi, n_lat + 1)[1:-1]
    ph = np.linspace(0.0, 2 * math.pi, n_lon, endpoint=False)
    t, f = np.meshgrid(th, ph, indexing="ij")
    unit = np.stack([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)], -1).reshape(-1, 3)
    unit = np.vstack([unit, [[0, 0, 1], [0, 0, -1]]])
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    verts = (unit * radii) @ rot.T + center
    normals = (unit / np.asarray(radii)) @ rot.T
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    rings, top, bottom = n_lat - 1, len(unit) - 2, len(unit) - 1
    tris = []
    for j in range(n_lon):
        k = (j + 1) % n_lon
        tris.append((top, j, k))
        tris.append((bottom, (rings - 1) * n_lon + k, (rings - 1) * n_lon + j))
        for i in range(rings - 1):
            a, b, c2, d = i * n_lon + j, i * n_lon + k, (i + 1) * n_lon + j, (i + 1) * n_lon + k
            tris += [(a, c2, b), (b, c2, d)]
    return verts, normals, np.array(tris)


def _cylinder(center, radius: float, height: float, n_seg: int, n_rings: int = 1):
    """Closed z-axis cylinder with its base at center: 2 * n_seg * n_rings + 2 * n_seg triangles."""
    ang = np.linspace(0.0, 2 * math.pi, n_seg, endpoint=False)
    ring = np.stack([np.cos(ang), np.sin(ang), np.zeros(n_seg)], -1)
    zs = np.linspace(0.0, height, n_rings + 1)
    side = np.vstack([ring * [radius, radius, 0] + [0, 0, z] for z in zs]) + center
    verts = np.vstack([side, [np.add(center, (0, 0, height)), np.asarray(center, dtype=float)]])
    normals = np.vstack([np.tile(ring, (n_rings + 1, 1)), [[0, 0, 1], [0, 0, -1]]])
    top, bottom, tris = len(verts) - 2, len(verts) - 1, []
    for r in range(n_rings):
        for j in range(n_seg):
            k = (j + 1) % n_seg
            a, b, c, d = r * n_seg + j, r * n_seg + k, (r + 1) * n_seg + j, (r + 1) * n_seg + k
            tris += [(a, b, c), (b, d, c)]
    for j in range(n_seg):
        k = (j + 1) % n_seg
        tris += [(top, n_rings * n_seg + j, n_rings * n_seg + k), (bottom, k, j)]
    return verts, normals, np.array(tris)


def _box(center, size, n_div: int = 1):
    """Axis-aligned box whose faces are n_div x n_div grids: 12 * n_div**2 triangles."""
    verts, normals, tris = [], [], []
    half = np.asarray(size, dtype=float) / 2
    g = np.linspace(-1.0, 1.0, n_div + 1)
    for axis in range(3):
        for sign in (-1.0, 1.0):
            u, v = [a for a in range(3) if a != axis]
            base = len(verts)
            for gu in g:
                for gv in g:
                    p = np.zeros(3)
                    p[axis], p[u], p[v] = sign, gu, gv
                    verts.append(p * half + center)
                    n = np.zeros(3)
                    n[axis] = sign
                    normals.append(n)
            for i in range(n_div):
                for j in range(n_div):
                    a, b = base + i * (n_div + 1) + j, base + (i + 1) * (n_div + 1) + j
                    quad = [(a, b, a + 1), (a + 1, b, b + 1)]
                    tris += quad if sign > 0 else [(x, z, y) for x, y, z in quad]
    return np.array(verts), np.array(normals), np.array(tris)


def _crazyflie_like_parts(total: int):
    """(name, (verts, normals, tris), instance offsets) in millimetres, z up; about ``total`` triangles overall.

    The layout follows cf2.dae's: motors on a 92 mm diagonal, motor mounts hanging from 5 mm down to -12.5 mm
    (the legs), a 37 mm plate about 4 mm up with the battery under it and the header pins above, and four
    two-blade propellers of 23 mm radius whose hubs sit about 12.7 mm up. The propeller is one geometry
    instanced four times, as in cf2.dae; the plate's tessellation absorbs the difference to ``total``.
    """
    motors = [(sx * 32.6, sy * 32.6) for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    parts = []
    for i, (x, y) in enumerate(motors):
        parts.append((f"mount{i}", _cylinder((x, y, -12.5), 4.3, 17.3, 40, 3), [(0, 0, 0)]))  # 320
        d = np.array([x, y]) / np.hypot(x, y)
        arm = (d[0] * 17.0, d[1] * 17.0, 4.0)
        parts.append((f"arm{i}", _ellipsoid(arm, (14.0, 2.5, 1.5), 12, 3, yaw=math.atan2(y, x)), [(0, 0, 0)]))
        parts.append((f"motor{i}", _cylinder((x, y, 4.8), 3.5, 6.5, 32, 1), [(0, 0, 0)]))  # 128
    for i in range(20):  # header pins
        x, y = -9.5 + (i % 10) * 2.1, (1 if i < 10 else -1) * 14.0
        parts.append((f"pin{i}", _cylinder((x, y, 5.0), 0.4, 8.0, 8, 1), [(0, 0, 0)]))  # 32
    parts.append(("battery", _box((0.0, 0.0, -0.5), (30.0, 17.0, 7.5), 4), [(0, 0, 0)]))  # 192
    parts.append(("deck", _ellipsoid((0.0, 0.0, 7.0), (12.0, 9.0, 2.0), 40, 12), [(0, 0, 0)]))  # 880
    propeller = _ellipsoid((0.0, 0.0, 0.0), (23.0, 3.5, 0.8), 36, 12)  # 792
    parts.append(("propeller", propeller, [(x, y, 12.7) for x, y in motors]))
    used = sum(len(p[1][2]) * len(p[2]) for p in parts)
    n_div = max(1, round(math.sqrt(max(total - used, 12) / 12)))
    parts.append(("plate", _box((0.0, 0.0, 4.2), (37.0, 37.0, 1.6), n_div), [(0, 0, 0)]))
    return parts


def _collada(parts) -> str:
    """COLLADA 1.4 text in the form cf2.dae uses: triangle polylists with normals, one node per instance."""
    geos, nodes = [], []
    for name, (welded, normals, tris), offsets in parts:
        # Like the Blender export, about one position per triangle: every other triangle uses a copy of the
        # vertex array, and normals are indexed separately, so the text (and the parse) is of cf2.dae's size.
        verts = np.vstack([welded, welded])
        vidx = tris + (np.arange(len(tris)) % 2 * len(welded))[:, None]
        pos = " ".join(f"{v:.6g}" for v in verts.ravel())
        nor = " ".join(f"{v:.7g}" for v in normals.ravel())
        idx = " ".join(f"{a} {n}" for a, n in zip(vidx.ravel(), tris.ravel(), strict=True))
        geos.append(
            f'<geometry id="{name}-mesh" name="{name}"><mesh>'
            f'<source id="{name}-pos"><float_array id="{name}-pos-array" count="{verts.size}">{pos}</float_array>'
            f'<technique_common><accessor source="#{name}-pos-array" count="{len(verts)}" stride="3">'
            '<param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>'
            "</accessor></technique_common></source>"
            f'<source id="{name}-nor"><float_array id="{name}-nor-array" count="{normals.size}">{nor}</float_array>'
            f'<technique_common><accessor source="#{name}-nor-array" count="{len(normals)}" stride="3">'
            '<param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>'
            "</accessor></technique_common></source>"
            f'<vertices id="{name}-vtx"><input semantic="POSITION" source="#{name}-pos"/></vertices>'
            f'<polylist material="grey" count="{len(tris)}">'
            f'<input semantic="VERTEX" source="#{name}-vtx" offset="0"/>'
            f'<input semantic="NORMAL" source="#{name}-nor" offset="1"/>'
            f"<vcount>{' '.join(['3'] * len(tris))}</vcount><p>{idx}</p></polylist></mesh></geometry>"
        )
        for k, (x, y, z) in enumerate(offsets):
            nodes.append(
                f'<node id="{name}-{k}" name="{name}-{k}" type="NODE">'
                f'<matrix sid="transform">1 0 0 {x} 0 1 0 {y} 0 0 1 {z} 0 0 0 1</matrix>'
                f'<instance_geometry url="#{name}-mesh"/></node>'
            )
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n'
        '<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">'
        '<asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>'
        f"<library_geometries>{''.join(geos)}</library_geometries>"
        '<library_visual_scenes><visual_scene id="Scene" name="Scene">'
        '<node id="body" name="body" type="NODE"><matrix sid="transform">'
        "0.001 0 0 0 0 0.001 0 0 0 0 0.001 0 0 0 0 1</matrix>"
        f"{''.join(nodes)}</node></visual_scene></library_visual_scenes>"
        '<scene><instance_visual_scene url="#Scene"/></scene></COLLADA>\n'
    )


def _drone_urdf(mesh_file: str) -> str:
    """cf2x.urdf's links, masses, inertia and shapes, with the generated mesh as the visual."""
    props = "".join(
        f'<link name="{name}"><inertial><origin rpy="0 0 0" xyz="{xyz}"/><mass value="0"/>'
        '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>'
        f'<joint name="{name}_joint" type="fixed"><parent link="base_link"/><child link="{name}"/></joint>'
        for name, xyz in (("prop0_link", "0.028 0.028 0"), ("prop1_link", "-0.028 0.028 0"),
                          ("prop2_link", "-0.028 -0.028 0"), ("prop3_link", "0.028 -0.028 0"),
                          ("center_of_mass_link", "0 0 0"))
    )
    return (
        '<?xml version="1.0" ?><robot name="cf2x_like"><link name="base_link">'
        f'<inertial><origin rpy="0 0 0" xyz="0 0 0"/><mass value="{MASS}"/>'
        '<inertia ixx="1.4e-5" ixy="0" ixz="0" iyy="1.4e-5" iyz="0" izz="2.17e-5"/></inertial>'
        f'<visual><origin rpy="0 0 55" xyz="0 0 0"/><geometry><mesh filename="{mesh_file}" scale="1 1 1"/>'
        '</geometry><material name="grey"><color rgba=".5 .5 .5 1"/></material></visual>'
        f'<collision><origin rpy="0 0 0" xyz="0 0 0"/><geometry><cylinder radius="{COLLISION_R}" '
        f'length="{COLLISION_H}"/></geometry></collision></link>{props}</robot>\n'
    )


def mesh_triangles(parts) -> int:
    return sum(len(tris) * len(offsets) for _, (_, _, tris), offsets in parts)


# ----------------------------------------------------------------------------------------------------------


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
        parts = _crazyflie_like_parts(config.drone_triangles)
        self.drone_triangles = mesh_triangles(parts)
        with open(os.path.join(self._dir, "cf2_like.dae"), "w") as f:
            f.write(_collada(parts))
        self.urdf = os.path.join(self._dir, "cf2x_like.urdf")
        with open(self.urdf, "w") as f:
            f.write(_drone_urdf("cf2_like.dae"))
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
            forces = rpm[0] ** 2 * KF
            torques = rpm[0] ** 2 * KM
            z_torque = -torques[0] + torques[1] - torques[2] + torques[3]
            for i in range(4):
                pb.applyExternalForce(drone, i, forceObj=[0, 0, forces[i]], posObj=[0, 0, 0],
                                      flags=pb.LINK_FRAME, physicsClientId=cid)
            pb.applyExternalTorque(drone, 4, torqueObj=[0, 0, z_torque], flags=pb.LINK_FRAME,
                                   physicsClientId=cid)
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


# ----------------------------------------------------------------------------------------------------------


def measure(workload: DroneCameraWorkload, steps: int, warmup: int, seed: int = 0) -> dict[str, float]:
    """Steps/s over ``steps`` uniform-random actions after ``warmup`` untimed ones, resetting when an episode
    ends as a gym training loop would (reset time counted, as it is in a training run's throughput).

    Wall-clock and process CPU time are both kept: on a shared machine the CPU-time figure is the steadier one.
    """
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, size=(warmup + steps, 1, 4)).astype(np.float32)
    workload.reset()
    for a in actions[:warmup]:
        _, _, terminated, truncated, _ = workload.step(a)
        if terminated or truncated:
            workload.reset()
    step_s = reset_s = step_cpu = reset_cpu = 0.0
    resets, images0 = 0, workload.images
    for a in actions[warmup:]:
        t0, c0 = time.perf_counter(), time.process_time()
        _, _, terminated, truncated, _ = workload.step(a)
        t1, c1 = time.perf_counter(), time.process_time()
        step_s, step_cpu = step_s + t1 - t0, step_cpu + c1 - c0
        if terminated or truncated:
            workload.reset()
            reset_s, reset_cpu = reset_s + time.perf_counter() - t1, reset_cpu + time.process_time() - c1
            resets += 1
    return {
        "steps_per_s": steps / (step_s + reset_s),
        "steps_per_s_without_resets": steps / step_s,
        "steps_per_cpu_s": steps / (step_cpu + reset_cpu),
        "steps_per_cpu_s_without_resets": steps / step_cpu,
        "resets": resets,
        "reset_ms": 1e3 * reset_s / max(resets, 1),
        "images_per_step": (workload.images - images0) / steps,
    }


def _row(scene: str, ctrl_freq: int, r: dict[str, float]) -> str:
    n = 240 // ctrl_freq
    return (f"| {scene} | {ctrl_freq} Hz ({n} substep{'s' if n > 1 else ''}) | {r['images_per_step']:.2f} | "
            f"{r['steps_per_s_without_resets']:,.0f} | {r['steps_per_s']:,.0f} | "
            f"{r['steps_per_cpu_s_without_resets']:,.0f} | {r['resets']} x {r['reset_ms']:.0f} ms |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("--ctrl-freq", type=int, default=48, help="24, 48, 120 or 240 (Hz)")
    parser.add_argument("--scene", choices=("rl", "vision_aviary"), default="rl")
    parser.add_argument("--drone-triangles", type=int, default=DRONE_TRIANGLES)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sweep", action="store_true", help="every allowed control rate, both scenes")
    args = parser.parse_args()
    configs = ([(scene, f) for scene in ("rl", "vision_aviary") for f in (24, 48, 120, 240)] if args.sweep
               else [(args.scene, args.ctrl_freq)])
    print(f"gym-pybullet-drones HoverAviary(obs=RGB) workload, reconstructed: 240 Hz physics, 64x48 TinyRenderer "
          f"image at 24 FPS, shadow=1; {args.steps} uniform-random-action steps after {args.warmup} warm-up\n")
    print("| scene | control | images/step | steps/s, step() only | steps/s, resets included | "
          "steps per CPU-s, step() only | resets |\n|---|---|---|---|---|---|---|")
    for scene, ctrl_freq in configs:
        workload = make_drone_camera_workload(ctrl_freq=ctrl_freq, scene=scene,
                                              drone_triangles=args.drone_triangles)
        try:
            r = measure(workload, args.steps, args.warmup, args.seed)
        finally:
            workload.close()
        print(_row(scene, ctrl_freq, r), flush=True)
    print(f"\ndrone visual mesh: {workload.drone_triangles} triangles (cf2.dae stand-in)")


if __name__ == "__main__":
    main()
