"""The rebuilt peer's drone: cf2x.urdf's links, mass and inertia, and a generated stand-in for its visual mesh.

From ``gym_pybullet_drones/assets/cf2x.urdf`` (the version read is named in :mod:`benchmarks.peers.drones`):
base_link: mass 0.027 kg, inertia diag(1.4e-5, 1.4e-5, 2.17e-5) (``URDF_USE_INERTIA_FROM_FILE``), collision
cylinder r = 0.06, length 0.025; five massless fixed child links (prop0..3, center_of_mass), so it is a 5-link
multibody; visual mesh with origin rpy (0, 0, 55); start (0, 0, 0.1125).

What could not be reproduced, and the stand-in: the Crazyflie visual mesh ``cf2.dae`` (COLLADA, 530 kB) is not
available here and is not copied. Its triangle count matters to TinyRenderer, which transforms and clips every
triangle of every body in both the shadow pass and the colour pass. From the stored file: 37 geometries written as
triangle ``polylist``s with positions and separately indexed normals, a 792-triangle propeller instanced 4 times,
motor mounts of 328-330 and 36 triangles, millimetre units under a 0.001-scale root node. Only part of the file was
read, so the total is an estimate from its text density: about 8,200 triangles (roughly 7,000-9,500). The stand-in
is a generated COLLADA file of the same form (one geometry per part, ``polylist`` with normals, the propeller
geometry instanced 4 times, 0.001 root scale, about one position per triangle) with ``DRONE_TRIANGLES`` triangles
laid out like cf2.dae's parts (plate, four arms, leg-like mounts, motors, pins, four 46 mm two-blade propellers with
hubs 12.7 mm up, as the stored file places them) and a text of 377 kB, so the rendering cost and the mesh-parsing
cost of each reset are of the same size. Its shapes are not the real ones. Measured sensitivity: about 0.27 ms of
CPU per image per 1,000 drone triangles (the whole drone costs about 1.9 ms of a 5.6 ms image), so the 7,000-9,500
range moves steps/s by about 5% either way.
"""

from __future__ import annotations

import math
import os

import numpy as np

MASS = 0.027
COLLISION_H, COLLISION_R, COLLISION_Z_OFFSET = 0.025, 0.06, 0.0
DRONE_TRIANGLES = 8200  # estimate of cf2.dae's triangle count (instances included), see the module docstring


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


def write_drone(folder: str, triangles: int = DRONE_TRIANGLES) -> tuple[str, int]:
    """Write the stand-in mesh and the URDF into ``folder``; (the URDF's path, the mesh's triangle count)."""
    parts = _crazyflie_like_parts(triangles)
    with open(os.path.join(folder, "cf2_like.dae"), "w") as f:
        f.write(_collada(parts))
    urdf = os.path.join(folder, "cf2x_like.urdf")
    with open(urdf, "w") as f:
        f.write(_drone_urdf("cf2_like.dae"))
    return urdf, mesh_triangles(parts)
