"""Fields a user colours by in ParaView: strains, stress resultants, curvatures, thickness strain,
contact gap and pressure, flags and refinement level -- per element (cell data) and per node (point
data) of a state U.

The element kernels return energies, forces and tangents only; the strains here are the same
quantities they integrate (elements/core.py's docstring, Eqs. 2-8), evaluated once per written
state, batched over each element block in numpy:

* membrane strains eps = (eps_xx, eps_yy, gamma_xy) [-] and bending strains (curvatures)
  kappa = (kappa_xx, kappa_yy, kappa_xy) [1/cm] of Eq. (6) in the local frame of Eq. (6): x along
  the fabric's warp projected on the tangent plane, y = z x x the weft (elements/frames.py); for a
  quad with the assumed membrane ("ans", quad4.py) the assumed field the element uses;
* transverse shears (gamma_zx, gamma_zy) [-] from the ANS tying values (Eq. 4; Eqs. 13-14 for
  triangles);
* stress resultants N = C_m eps [gf/cm], M = C_b kappa [gf cm/cm], Q = C_t gamma [gf/cm] with the
  section's rigidities (material.py) -- with M's sign that of kappa, M = dW/dkappa;
* each element's value is the J_o-weighted mean over its integration points (Eq. 8);
* a node's value is the mean of its elements' values weighted by its trapezoidal area share in each
  (the lumped-mass areas of Section 4), so a uniform field stays uniform;
* thickness strain per node: the model's own eps_zz (Green: x_n.x_n/2 - X_n.X_n/2, Eq. 5; with
  thickness_strain = "quasi", |x_n| - |X_n| of Eq. 24 without its sign switch); per element, the
  mean of its nodes';
* per rigid body b: ``gap:<b>`` [cm] = g(x) - offset of every node (negative: inside the
  sheet's offset from the body) and ``contact_pressure:<b>`` [gf/cm^2]: the reaction the body
  carries at a node, (F_int - lambda P) . n_b / A_node, for free nodes within a thickness h of the
  body (gap < h; a node near two bodies goes to the closer), 0 elsewhere -- from equilibrium, so
  whatever the contact law (penalty, augmented Lagrangian, face points), at a converged or resting
  state it is the force the solver's contact exerts; in a moving frame of an explicit run it also
  carries the node's inertia and damping;
* flags: ``interpenetrated`` (n_p . d_p < 0 at a corner, Section 4.3: Model.interpenetration),
  ``self_intersecting`` (an element whose mid-surface triangles cross another's that shares no node:
  solidshell/layers.py), ``layers_close`` (a node of two layers of the sheet closer than the
  thickness less 10 %: self-contact, layers.py), ``clamped`` (a node with all six dofs fixed);
* adaptive meshes: the tags the adaptive driver puts on each active mesh (``mesh.cell_tags``):
  ``refinement_level`` (a transition element between levels i and i+1: i + 1/2),
  ``transition_pattern`` (0: a plain leaf) and ``assumed_membrane``; every mesh gets
  ``element_type`` (4 quad, 3 triangle).

The whole sheet: pedestal scenes mesh only the hanging part (DESIGN: conventions); the part lying
clamped on the pedestal is every inner boundary loop whose nodes are all clamped, written as one
flat polygon cell per loop (:func:`clamped_patches`) with zero strains and resultants and
``clamped_part`` = 1.
"""

from __future__ import annotations

import numpy as np

from .elements import quad4, tri3
from .elements.frames import covariant_maps, local_frame

COMPONENTS = ("xx", "yy", "xy")
"""Suffixes of the in-plane fields: x the warp, y the weft, xy the (engineering) shear."""

CELL_ONLY = ("element_type", "refinement_level", "transition_pattern", "assumed_membrane")
"""Cell fields not averaged to the nodes (labels, not quantities)."""


def _dot(a, b):
    return np.sum(a * b, -1)


def _tangents(dN, x):
    """(M,G,2,3) natural tangents sum_i dN_gik x_i of element nodal vectors x (M,nn,3)."""
    return np.einsum("gik,mic->mgkc", dN, x)


def _block_strains(b, X, D, U, warp):
    """(eps (M,3), kappa (M,3), gamma (M,2)) element means of one model block (module docstring)."""
    conn = b.conn
    Xe, De, Ue, Ve = X[conn], D[conn], U[conn, :3], U[conn, 3:]
    A = _tangents(b.dN, Xe)
    B = _tangents(b.dN, De)
    u = _tangents(b.dN, Ue)
    v = _tangents(b.dN, Ve)
    A1, A2, B1, B2, u1, u2, v1, v2 = (t[:, :, k] for t in (A, B, u, v) for k in (0, 1))

    def prod(a, b_, du, dv):  # a.b - A.B in the displacement form of Eq. (3): u.B + A.v + u.v
        return _dot(du, b_) + _dot(a, dv) + _dot(du, dv)

    e_nat = np.stack([_dot(u1, A1 + 0.5 * u1), _dot(u2, A2 + 0.5 * u2), prod(A1, A2, u1, u2)], -1)
    k_nat = np.stack([prod(A1, B1, u1, v1), prod(A2, B2, u2, v2), prod(A1, B2, u1, v2) + prod(A2, B1, u2, v1)], -1)
    T = b.c["T"]  # (M,G,3,3): natural -> local Voigt strains (Eq. 6)
    quad = b.module is quad4
    Jw = b.c["J"] * b.module.GAUSS_W  # (M,4) quads; (M,3) triangles (shear points)
    if quad and len(b.tie) > len(quad4.TIE):  # assumed membrane: the field the element integrates
        P, WF = quad4.assumed_membrane_field(Xe, Jw)
        d = _tying_diff(quad4.M_ALPHA, quad4.M_BETA, quad4.M_TIE[:, 2], Xe, Xe, Ue, Ue)  # (M,22)
        e_nat = np.einsum("mgap,mp->mga", WF, np.einsum("mpt,mt->mp", P, d))
    eps = np.einsum("mgab,mgb->mga", T, e_nat)
    kap = np.einsum("mgab,mgb->mga", T, k_nat)
    # transverse shear (gamma_zx, gamma_zy) at the shear points from the tying values
    alpha, beta = b.module.ALPHA, b.module.BETA
    s = _tying_diff(alpha, beta, np.ones(len(alpha)), Xe, De, Ue, Ve)  # (M,nt)
    if quad:
        ex, ey, _ = local_frame(A1, A2, warp)
        Q, _ = covariant_maps(A1, A2, ex, ey)  # (M,4,2,2)
        gam = np.einsum("mgab,gbt,mt->mga", Q, quad4.S_GP, s)
        w = Jw / Jw.sum(1, keepdims=True)
        return (np.einsum("mg,mga->ma", w, eps), np.einsum("mg,mga->ma", w, kap), np.einsum("mg,mga->ma", w, gam))
    ex, ey, _ = local_frame(A1[:, 0], A2[:, 0], warp)
    gam = np.einsum("mgat,mt->mga", tri3.shear_map(Xe, ex, ey), s)
    w = Jw / Jw.sum(1, keepdims=True)
    return eps[:, 0], kap[:, 0], np.einsum("mg,mga->ma", w, gam)


def _tying_diff(alpha, beta, c, Ya, Yb, Ua, Ub):
    """(M,nt) c_t [(alpha_t . y_a)(beta_t . y_b)] at Y + U minus at Y, in displacement form."""
    a, b = np.einsum("ti,mic->mtc", alpha, Ya), np.einsum("ti,mic->mtc", beta, Yb)
    du, dv = np.einsum("ti,mic->mtc", alpha, Ua), np.einsum("ti,mic->mtc", beta, Ub)
    return c * (_dot(du, b) + _dot(a, dv) + _dot(du, dv))


def element_fields(model, U) -> dict:
    """Cell fields of the state U (N,6) on the model's elements (quads, then triangles: the mesh's
    order): ``membrane_strain_<c>``, ``N_<c>``, ``curvature_<c>``, ``M_<c>`` (c in COMPONENTS),
    ``shear_strain_xz/_yz``, ``Q_xz/_yz``, ``thickness_strain``, ``element_type`` (module docstring)."""
    mesh, mat = model.mesh, model.material
    X, D = np.asarray(mesh.nodes, float), np.asarray(mesh.directors, float)
    U = np.asarray(U, dtype=float).reshape(mesh.n_nodes, 6)
    parts = [_block_strains(b, X, D, U, float(mat.warp_angle_rad)) for b in model.blocks]
    eps, kap, gam = (np.concatenate([p[i] for p in parts]) for i in range(3))
    N, M, Qs = eps @ np.asarray(mat.C_m).T, kap @ np.asarray(mat.C_b).T, gam @ np.asarray(mat.C_t).T
    out = {}
    for j, c in enumerate(COMPONENTS):
        out[f"membrane_strain_{c}"] = eps[:, j]
        out[f"N_{c}"] = N[:, j]
        out[f"curvature_{c}"] = kap[:, j]
        out[f"M_{c}"] = M[:, j]
    for j, c in enumerate(("xz", "yz")):
        out[f"shear_strain_{c}"] = gam[:, j]
        out[f"Q_{c}"] = Qs[:, j]
    ez = thickness_strain(model, U)
    out["thickness_strain"] = np.concatenate([ez[b.conn].mean(1) for b in model.blocks])
    out["element_type"] = np.concatenate([np.full(len(b.conn), b.nn, dtype=np.int32) for b in model.blocks])
    return out


def thickness_strain(model, U) -> np.ndarray:
    """(N,) the model's thickness strain at each node (Eq. 5 Green, or Eq. 24's |x_n| - |X_n|)."""
    D = np.asarray(model.mesh.directors, float)
    V = np.asarray(U, dtype=float).reshape(-1, 6)[:, 3:]
    if model.quasi:
        return np.linalg.norm(D + V, axis=1) - np.linalg.norm(D, axis=1)
    return _dot(V, D + 0.5 * V)


def nodal_average(model, cell: dict) -> dict:
    """Each cell field averaged to the nodes with the trapezoidal area shares as weights."""
    X, D = model.mesh.nodes, model.mesh.directors
    n = model.n_nodes
    conn = [b.conn for b in model.blocks]
    w = [b.module.nodal_areas(X[c], D[c]) for b, c in zip(model.blocks, conn)]
    idx = np.concatenate([c.ravel() for c in conn])
    wf = np.concatenate([x.ravel() for x in w])
    den = np.bincount(idx, wf, minlength=n)
    den = np.where(den > 0.0, den, 1.0)
    per = np.concatenate([np.full(len(c), c.shape[1]) for c in conn])  # each element's node count
    out = {}
    for k, f in cell.items():
        if k not in CELL_ONLY:
            out[k] = np.bincount(idx, wf * np.repeat(np.asarray(f, float), per), minlength=n) / den
    return out


def body_labels(bodies) -> list[str]:
    """A short unique name per contact body: its class name in lower case, numbered when repeated."""
    names = [type(b).__name__.lower() for b in bodies]
    return [f"{m}{names[:i].count(m) + 1}" if names.count(m) > 1 else m for i, m in enumerate(names)]


def contact_fields(problem, U, load_factor: float = 1.0) -> dict:
    """Point fields ``gap:<body>`` [length] and ``contact_pressure:<body>`` [force/length^2] of the
    problem's rigid bodies at U (module docstring); empty without bodies."""
    bodies = list(problem.contact or [])
    if not bodies:
        return {}
    model = problem.model
    U = np.asarray(U, dtype=float).reshape(model.n_nodes, 6)
    x = model.mesh.nodes + U[:, :3]
    h = float(model.material.thickness)
    R = model.internal_force(U)[:, :3] - float(load_factor) * problem.loads[:, :3]  # the bodies' reaction
    free = ~np.asarray(problem.fixed, bool)[:, :3].all(axis=1)
    A = model.nodal_areas()
    gaps, normals = zip(*(b.penetration(x) for b in bodies))
    G = np.stack(gaps)  # (B,N)
    near = np.argmin(G, axis=0)
    out = {}
    for i, name in enumerate(body_labels(bodies)):
        on = free & (near == i) & (G[i] < h)
        p = np.zeros(model.n_nodes)
        p[on] = np.maximum(0.0, _dot(R[on], normals[i][on])) / A[on]
        out[f"gap:{name}"] = G[i].copy()
        out[f"contact_pressure:{name}"] = p
    return out


def flag_fields(model, U, self_intersection: bool = True) -> tuple[dict, dict]:
    """(point, cell) 0/1 fields ``interpenetrated`` and ``self_intersecting`` (module docstring)."""
    mesh = model.mesh
    nq = len(mesh.quads)
    nd = model.interpenetration(U)
    cell = {"interpenetrated": np.concatenate([(a < 0.0).any(1) for a in nd]).astype(np.int8)}
    point = {"interpenetrated": model.interpenetrated_nodes(U).astype(np.int8)}
    if self_intersection:
        from .layers import self_intersections

        t = np.unique(self_intersections(mesh, U).ravel())  # layers.triangles(): quads split in two, then tris
        e = np.where(t < 2 * nq, t % max(nq, 1), t - nq)
        cf = np.zeros(mesh.n_elements, dtype=np.int8)
        cf[e] = 1
        pf = np.zeros(mesh.n_nodes, dtype=np.int8)
        for c, off in ((mesh.quads, 0), (mesh.tris, nq)):
            pf[np.asarray(c)[cf[off : off + len(c)] > 0].ravel()] = 1
        cell["self_intersecting"], point["self_intersecting"] = cf, pf
        # self-contact: nodes of two layers closer than the thickness less LAYER_TOL (layers.py)
        from .layers import LAYER_TOL, layer_pairs

        h = float(model.material.thickness)
        d, nodes = layer_pairs(mesh, U, h)
        close = np.zeros(mesh.n_nodes, dtype=np.int8)
        hit = [n for dk, n in zip(d, nodes) if dk < (1.0 - LAYER_TOL) * h]
        if hit:
            close[np.unique(np.concatenate([np.asarray(n, dtype=np.int64) for n in hit]))] = 1
        point["layers_close"] = close
    return point, cell


def state_fields(problem, U, load_factor: float = 1.0, self_intersection: bool = True) -> tuple[dict, dict]:
    """(point data, cell data) of the state U (N,6) of ``problem`` (a solidshell.problem.Problem):
    everything of the module docstring, ready for meshio."""
    model = problem.model
    mesh = model.mesh
    U = np.asarray(U, dtype=float).reshape(model.n_nodes, 6)
    cell = element_fields(model, U)
    for k, v in (getattr(mesh, "cell_tags", None) or {}).items():
        cell[k] = np.asarray(v)
    point = nodal_average(model, cell)
    point["thickness_strain"] = thickness_strain(model, U)
    point["clamped"] = np.asarray(problem.fixed, bool).all(axis=1).astype(np.int8)
    point.update(contact_fields(problem, U, load_factor))
    fp, fc = flag_fields(model, U, self_intersection)
    point.update(fp)
    cell.update(fc)
    return point, cell


def clamped_patches(mesh, fixed) -> list[np.ndarray]:
    """The sheet's clamped parts that are not meshed: each inner boundary loop (a hole) whose nodes
    all have all six dofs fixed, as node indices ordered counter-clockwise seen from the directors'
    side -- the sheet lying on a pedestal.  Empty when there is none."""
    from .analysis import boundary_loops, polygon_area

    fixed = np.asarray(fixed, bool).reshape(mesh.n_nodes, 6).all(axis=1)
    loops = boundary_loops(mesh.boundary_edges())
    if len(loops) < 2:
        return []
    X = np.asarray(mesh.nodes, float)
    out = []
    for lp in loops:
        if not fixed[lp].all():
            continue
        # the loop's plane normal (Newell) against the mean director: holes run clockwise
        P = X[lp]
        nrm = np.cross(P, np.roll(P, -1, axis=0)).sum(0)
        if float(nrm @ np.asarray(mesh.directors, float)[lp].mean(0)) < 0.0:
            lp = lp[::-1]
        out.append(np.asarray(lp, dtype=np.int64))
    # the outer loop is never a hole: drop a loop that encloses all the others (largest area)
    if len(out) == len(loops):
        areas = [abs(polygon_area(X[lp][:, :2])) for lp in out]
        out.pop(int(np.argmax(areas)))
    return out
