"""Mesh bodies built from primitives with gmsh's OpenCASCADE kernel (``[[contact]] type = "mesh"``,
``primitives = [...]``): the example scenes' table, torso and shoulders need no shipped files.

Each primitive is a table with one key [cm]:

* ``sphere = [cx, cy, cz, r]``
* ``ellipsoid = [cx, cy, cz, rx, ry, rz]``  (a unit sphere dilated)
* ``box = [x0, y0, z0, dx, dy, dz]``  (a corner and the side lengths)
* ``cylinder = [x, y, z, ax, ay, az, r]``  (the base centre, the axis vector to the other end, radius)

The primitives are fused into one solid (boolean union), its boundary meshed with triangles of size
``mesh_size`` (default: 1/60 of the union's bounding-box diagonal), and the triangles oriented
consistently and outward (gmsh orients each OCC face on its own).
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

SHAPES = {"sphere": 4, "ellipsoid": 6, "box": 6, "cylinder": 7}
"""Primitive -> how many numbers it takes."""


def check_primitives(primitives, where: str) -> list[tuple[str, list[float]]]:
    if not isinstance(primitives, (list, tuple)) or not primitives:
        raise InputError(f"{where}: must be a non-empty array of tables, e.g. [{{sphere = [0, 0, 0, 5]}}]")
    out: list = []
    for i, p in enumerate(primitives):
        w = f"{where}[{i}]"
        if not isinstance(p, dict) or len(p) != 1 or next(iter(p)) not in SHAPES:
            raise InputError(f"{w}: must be one of {', '.join(f'{{{k} = [...]}}' for k in SHAPES)}, got {p!r}")
        k, v = next(iter(p.items()))
        try:
            vals = [float(x) for x in v]
        except (TypeError, ValueError):
            vals = []
        if len(vals) != SHAPES[k] or not np.all(np.isfinite(vals)):
            raise InputError(f"{w}.{k}: must be {SHAPES[k]} finite numbers, got {v!r}")
        sizes = {"sphere": vals[3:], "ellipsoid": vals[3:], "box": vals[3:], "cylinder": vals[6:]}[k]
        if k == "cylinder" and not np.linalg.norm(vals[3:6]) > 0.0:
            raise InputError(f"{w}.cylinder: the axis vector must be non-zero, got {v!r}")
        if any(s <= 0.0 for s in sizes):
            raise InputError(f"{w}.{k}: radii and side lengths must be positive, got {v!r}")
        out.append((k, vals))
    return out


def orient_outward(V, F):
    """F with its triangles turned consistently (libigl's bfs_orient, per connected patch) and each
    patch outward (positive enclosed volume)."""
    import igl

    FF, C = igl.bfs_orient(np.ascontiguousarray(F, np.int64))
    FF = np.asarray(FF, np.int64).copy()
    a, b, c = (V[FF[:, i]] for i in range(3))
    vol = np.einsum("ij,ij->i", a, np.cross(b, c))
    for comp in np.unique(C):
        sel = C == comp
        if vol[sel].sum() < 0.0:
            FF[sel] = FF[sel][:, ::-1]
    return FF


def surface(primitives, mesh_size=None, where: str = "primitives"):
    """(V, F) of the union of ``primitives`` (module docstring), meshed by gmsh."""
    from .meshing import _gmsh_model

    prims = check_primitives(primitives, where)
    with _gmsh_model("mesh_body") as gmsh:
        occ = gmsh.model.occ
        tags = []
        for k, v in prims:
            if k == "sphere":
                tags.append(occ.addSphere(*v))
            elif k == "ellipsoid":
                t = occ.addSphere(v[0], v[1], v[2], 1.0)
                occ.dilate([(3, t)], v[0], v[1], v[2], v[3], v[4], v[5])
                tags.append(t)
            elif k == "box":
                tags.append(occ.addBox(*v))
            else:
                tags.append(occ.addCylinder(*v))
        if len(tags) > 1:
            occ.fuse([(3, tags[0])], [(3, t) for t in tags[1:]])
        occ.synchronize()
        lo = np.array(gmsh.model.getBoundingBox(-1, -1)[:3])
        hi = np.array(gmsh.model.getBoundingBox(-1, -1)[3:])
        size = float(mesh_size) if mesh_size is not None else float(np.linalg.norm(hi - lo)) / 60.0
        if not size > 0.0:
            raise InputError(f"{where}: mesh_size must be positive, got {mesh_size!r}")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.2 * size)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)  # 12 elements per 2 pi of curvature
        gmsh.model.mesh.generate(2)
        tag, xyz, _ = gmsh.model.mesh.getNodes()
        V = np.asarray(xyz, float).reshape(-1, 3)
        index = np.zeros(int(tag.max()) + 1, np.int64)
        index[np.asarray(tag, np.int64)] = np.arange(len(tag))
        _, conn = gmsh.model.mesh.getElementsByType(2)
        F = index[np.asarray(conn, np.int64).reshape(-1, 3)]
    used, Fc = np.unique(F, return_inverse=True)
    V, F = V[used], Fc.reshape(-1, 3).astype(np.int64)
    return V, orient_outward(V, F)
