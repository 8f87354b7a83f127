"""Square plate under uniform pressure: solid-shell centre deflection vs the Kirchhoff series.

Plate [0,a]^2, a = 1, nu = 0.3, thickness h = a/100 and a/1000, E chosen so that D = E h^3/(12(1-nu^2))
= 1 and q = 1, so the Kirchhoff centre deflection is w_c = alpha (reference/plates.json:
SS 0.00406235, clamped 0.00126532).  Full plate, N x N quads (N = 4, 8, 16, 32), the same quads split
into two triangles along one diagonal ("/"), and along alternating diagonals ("x"); and distorted
quads ("quad~": interior nodes moved randomly by up to a quarter element, fixed seed).

Small deflection: one linear solve K(0) u = f.  Load: pressure q on the U_o,z dofs, lumped by the
nodal areas (q A/4 per quad corner, q A/3 per triangle corner; for bilinear/linear interpolation of
w on a flat uniform mesh this equals the consistent load).

Boundary conditions (director-based shell, U_n ~ (-w_x, -w_y, 0) in the Kirchhoff limit):
* clamped: U_o = 0 and U_n = 0 on the edge nodes;
* simply supported, "hard" (primary): U_o = 0 and the tangential component of U_n = 0 (on x = const
  edges U_n,y = 0, on y = const edges U_n,x = 0).  This is the Reissner-Mindlin hard support: the
  rotation about the edge normal is zero, like the Kirchhoff plate along a straight supported edge
  (w = 0 along the edge => dw/ds = 0), and it has no boundary layer, so it converges to Navier;
* simply supported, "soft": U_o = 0 only, U_n free (the rotation about the normal is free).  For a
  Reissner-Mindlin plate this has a boundary layer of width ~h and converges to Navier only as
  h/a -> 0; reported for comparison (its differences from "hard" measure that layer, not an error).
Membrane dofs are fixed in both SS cases; in a linear solve of a flat plate membrane and bending are
uncoupled, so the in-plane constraint does not change w.

The shear deformation of a Reissner-Mindlin plate adds to w_c, for the hard SS plate exactly
Marcus' moment sum M_c/(kappa G h) (reference/plates.json "mindlin_ss_shear_coefficient"): a relative
5.2 (h/a)^2, i.e. 5e-4 at a/h = 100 and 5e-6 at a/h = 1000 -- below the errors measured here; the
comparison is with the Kirchhoff value.

The triangle: ``triangle_vs_mitc3`` compares it with an independent MITC3 plate code written here
(same shear interpolation, Eqs. 12-14 on a flat mesh); they agree to round-off, so the strong
thin-plate locking of the triangle on these structured meshes (error growing with a/h at fixed N)
is a property of the formulation (MITC3 is known not to be locking-free), not a coding error.

Run: ``python -m verification.plates [--quick]`` -> table, verification/out/plates.json, plates.png.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solidshell import IsotropicShell, Model, ShellMesh

from . import OUT, buckling_factors, linear_solve, plate_reference, rate, rect_grid, split_quads, write_json

NU = 0.3
A = 1.0


def square_plate_mesh(n: int, kind: str = "quad") -> ShellMesh:
    nodes, quads = rect_grid(n, n, A, A)
    if kind == "quad":
        return ShellMesh(nodes, quads=quads)
    if kind == "quad~":
        # distorted: interior nodes (except the centre) moved by up to +-1/4 of the element size in
        # x and y, fixed seed; the boundary stays straight
        rng = np.random.default_rng(12345)
        X = nodes.copy()
        inner = np.all((X[:, :2] > 1e-9 * A) & (X[:, :2] < A - 1e-9 * A), axis=1)
        inner[np.argmin(np.sum((X[:, :2] - 0.5 * A) ** 2, axis=1))] = False
        X[inner, :2] += rng.uniform(-0.25, 0.25, (int(inner.sum()), 2)) * A / n
        return ShellMesh(X, quads=quads)
    pattern = {"tri": "/", "tri/": "/", "tri\\": "\\", "trix": "x"}[kind]
    return ShellMesh(nodes, tris=split_quads(quads, pattern))


def plate_bc(mesh: ShellMesh, support: str) -> np.ndarray:
    X = mesh.nodes
    tol = 1e-9 * A
    on_x = (np.abs(X[:, 0]) < tol) | (np.abs(X[:, 0] - A) < tol)   # edges x = 0, a
    on_y = (np.abs(X[:, 1]) < tol) | (np.abs(X[:, 1] - A) < tol)   # edges y = 0, a
    edge = on_x | on_y
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[edge, :3] = True
    if support == "clamped":
        fixed[edge, 3:] = True
    elif support == "ss_hard":
        fixed[on_x, 4] = True      # U_n,y: the tangential component along x = const edges
        fixed[on_y, 3] = True      # U_n,x along y = const edges
    elif support != "ss_soft":
        raise ValueError(support)
    return fixed


def centre_deflection(n: int, kind: str, support: str, a_over_h: float) -> float:
    """-U_o,z at the centre for q = 1, D = 1 (so it equals alpha for a Kirchhoff plate)."""
    h = A / a_over_h
    E = 12.0 * (1.0 - NU**2) / h**3            # D = 1
    mesh = square_plate_mesh(n, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=NU, h=h))
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -1.0 * model.nodal_areas()   # q = 1 downwards
    U, _ = linear_solve(model, plate_bc(mesh, support), loads)
    ic = int(np.argmin(np.sum((mesh.nodes[:, :2] - 0.5 * A) ** 2, axis=1)))
    assert np.allclose(mesh.nodes[ic, :2], 0.5 * A)
    return float(-U[ic, 2])


def mitc3_plate(n: int, support: str, a_over_h: float, pattern: str = "/") -> float:
    """Centre deflection from an independent, minimal implementation of the MITC3 Reissner-Mindlin
    plate triangle (Bathe/Lee 2004; Hughes-Tezduyar shear), written here from its definition and
    sharing no code with solidshell: unknowns w, beta = (beta_x, beta_y) (= U_n,x, U_n,y, so the
    shear strain is grad w + beta and the curvatures sym grad beta), linear interpolation, shear
    from the three edge tangential values (w_j - w_i)/l + (beta_i + beta_j)/2 . t, extended as the
    lowest-order Nedelec (rotated Raviart-Thomas) field a + b (-y, x), integrated exactly.
    On a flat mesh the paper's Eqs. (12)-(14) produce this very field (a linear field whose
    tangential component is constant along each edge is the Nedelec field), so the solid-shell
    triangle must reproduce this to round-off in a linear plate problem."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    h = A / a_over_h
    E = 12.0 * (1.0 - NU**2) / h**3
    mat = IsotropicShell(E=E, nu=NU, h=h)
    nodes, quads = rect_grid(n, n, A, A)
    T = split_quads(quads, pattern)
    P = nodes[:, :2]
    ne = len(T)
    x = P[T]                                          # (ne,3,2)
    # gradients of the linear shape functions
    d1 = x[:, 1] - x[:, 0]
    d2 = x[:, 2] - x[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    area = 0.5 * det
    Jinv = np.stack([np.stack([d2[:, 1], -d2[:, 0]], -1), np.stack([-d1[:, 1], d1[:, 0]], -1)], -1) / det[:, None, None]
    dN_ref = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    G = np.einsum("ia,eab->eib", dN_ref, np.transpose(Jinv, (0, 2, 1)))   # (ne,3,2): dN_i/dx_b
    # element dof order: node i -> (w, bx, by) at 3i..3i+2
    Bb = np.zeros((ne, 3, 9))
    Bb[:, 0, 1::3] = G[:, :, 0]
    Bb[:, 1, 2::3] = G[:, :, 1]
    Bb[:, 2, 1::3] = G[:, :, 1]
    Bb[:, 2, 2::3] = G[:, :, 0]
    Kb = np.einsum("eki,kl,elj,e->eij", Bb, mat.C_b, Bb, area)
    # tying values g_e = B_t d for edges (0,1), (1,2), (2,0)
    Bt = np.zeros((ne, 3, 9))
    M3 = np.zeros((ne, 3, 3))
    for k, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        d = x[:, j] - x[:, i]
        l = np.linalg.norm(d, axis=1)
        t = d / l[:, None]
        Bt[:, k, 3 * j] += 1.0 / l
        Bt[:, k, 3 * i] -= 1.0 / l
        for c in range(2):
            Bt[:, k, 3 * i + 1 + c] += 0.5 * t[:, c]
            Bt[:, k, 3 * j + 1 + c] += 0.5 * t[:, c]
        m = 0.5 * (x[:, i] + x[:, j])
        M3[:, k] = np.column_stack([t[:, 0], t[:, 1], m[:, 0] * t[:, 1] - m[:, 1] * t[:, 0]])
    Cab = np.linalg.solve(M3, Bt)                     # (ne,3,9): (a_x, a_y, b) = Cab d
    # gamma(x) = a + b (-y, x): exact integration with the 3 mid-edge points (exact for quadratics)
    Ks = np.zeros((ne, 9, 9))
    kGh = mat.C_t[0, 0]
    for (i, j) in ((0, 1), (1, 2), (2, 0)):
        m = 0.5 * (x[:, i] + x[:, j])
        Bg = np.stack([Cab[:, 0] - m[:, 1, None] * Cab[:, 2], Cab[:, 1] + m[:, 0, None] * Cab[:, 2]], 1)
        Ks += kGh * np.einsum("eki,ekj,e->eij", Bg, Bg, area / 3.0)
    Ke = Kb + Ks
    dofs = (3 * T[:, :, None] + np.arange(3)).reshape(ne, 9)
    N = len(P)
    K = sp.coo_matrix((Ke.ravel(), (np.repeat(dofs, 9, 1).ravel(), np.tile(dofs, (1, 9)).ravel())),
                      shape=(3 * N, 3 * N)).tocsr()
    f = np.zeros(3 * N)
    np.add.at(f, 3 * T.ravel(), np.repeat(-area / 3.0, 3))
    tol = 1e-9 * A
    on_x = (np.abs(P[:, 0]) < tol) | (np.abs(P[:, 0] - A) < tol)
    on_y = (np.abs(P[:, 1]) < tol) | (np.abs(P[:, 1] - A) < tol)
    fixed = np.zeros((N, 3), dtype=bool)
    fixed[on_x | on_y, 0] = True
    if support == "clamped":
        fixed[on_x | on_y] = True
    elif support == "ss_hard":
        fixed[on_x, 2] = True
        fixed[on_y, 1] = True
    free = np.flatnonzero(~fixed.ravel())
    u = np.zeros(3 * N)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), f[free])
    ic = int(np.argmin(np.sum((P - 0.5 * A) ** 2, axis=1)))
    return float(-u[3 * ic])


def triangle_vs_mitc3(ns=(4, 8, 16, 32), ratios=(100.0, 1000.0), supports=("clamped", "ss_hard"), verbose=True):
    """The solid-shell triangle against the independent MITC3 implementation above."""
    rows = []
    if verbose:
        print("solid-shell triangle ('/' split) vs an independent MITC3 plate implementation:")
    for support in supports:
        for ah in ratios:
            for n in ns:
                w_ss = centre_deflection(n, "tri", support, ah)
                w_m = mitc3_plate(n, support, ah)
                rows.append(dict(support=support, a_over_h=ah, n=n, solid_shell=w_ss, mitc3=w_m,
                                 rel_difference=(w_ss - w_m) / w_m))
                if verbose:
                    print(f"  {support:8s} a/h={ah:6.0f} N={n:3d}  tri3 {w_ss:.8e}  MITC3 {w_m:.8e}  "
                          f"rel.diff {(w_ss - w_m) / w_m:+.2e}")
    return rows


def plate_buckling(n: int, kind: str = "quad", a_over_h: float = 100.0, k: int = 3) -> dict:
    """Linearised buckling of the hard simply supported square plate under uniaxial compression N_x
    (uniform, applied on the edge x = a, u_x = 0 on x = 0, u_y = 0 at one corner, the y-edges free to
    expand in-plane).  Closed form (Bryan 1891; T&W-K Theory of Elastic Stability): N_cr = k pi^2 D / a^2
    with k = (m + 1/m)^2 -> 4 (m = 1), 6.25 (m = 2), 11.11 (m = 3).  The pre-buckling membrane state is
    uniform (exact for both elements), so the error is that of the bending discretisation plus the
    element's geometric stiffness."""
    h = A / a_over_h
    E = 12.0 * (1.0 - NU**2) / h**3                  # D = 1
    mesh = square_plate_mesh(n, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=NU, h=h))
    X = mesh.nodes
    tol = 1e-9 * A
    fixed = plate_bc(mesh, "ss_hard")
    fixed[:, :2] = False                               # in-plane: only what removes rigid motion
    fixed[np.abs(X[:, 0]) < tol, 0] = True
    fixed[int(np.argmin(np.sum(X[:, :2] ** 2, axis=1))), 1] = True
    loads = np.zeros((mesh.n_nodes, 6))
    right = np.flatnonzero(np.abs(X[:, 0] - A) < tol)
    ys = np.sort(X[right, 1])
    for i in right:                                    # N_x = 1 compressive, edge-length shares
        j = np.searchsorted(ys, X[i, 1])
        lo = ys[j - 1] if j > 0 else X[i, 1]
        hi = ys[j + 1] if j + 1 < len(ys) else X[i, 1]
        loads[i, 0] = -0.5 * (hi - lo)
    lam, _ = buckling_factors(model, fixed, loads, k=k)
    kf = lam * A**2 / np.pi**2                         # buckling coefficients (D = 1)
    ref = np.array([4.0, 6.25, (3 + 1 / 3) ** 2])[:k]
    return dict(n=n, kind=kind, a_over_h=a_over_h, k=kf.tolist(), k_ref=ref.tolist(),
                rel_error=((kf - ref) / ref).tolist())


def run(ns=(4, 8, 16, 32), kinds=("quad", "quad~", "tri", "trix"), supports=("clamped", "ss_hard", "ss_soft"),
        ratios=(100.0, 1000.0), verbose=True):
    refs = plate_reference()
    ref = refs["alpha"]
    exact = {"clamped": ref["clamped"], "ss_hard": ref["simply_supported"], "ss_soft": ref["simply_supported"]}
    c_mindlin = refs.get("mindlin_ss_shear_coefficient")
    rows = []
    if verbose:
        print(f"{'support':8s} {'mesh':5s} {'a/h':>6s} {'N':>3s} {'w_c D/(q a^4)':>14s} {'rel.err':>10s} {'rate':>6s}")
    for support in supports:
        for kind in kinds:
            for ah in ratios:
                prev = None
                for n in ns:
                    t0 = time.perf_counter()
                    w = centre_deflection(n, kind, support, ah)
                    err = (w - exact[support]) / exact[support]
                    r = rate(prev, err) if prev is not None else None
                    row = dict(support=support, mesh=kind, a_over_h=ah, n=n, alpha=w, exact=exact[support],
                               rel_error=err, rate=r, seconds=time.perf_counter() - t0)
                    if support == "ss_hard" and c_mindlin is not None:
                        wm = exact[support] + c_mindlin / ah**2     # hard SS Reissner-Mindlin plate
                        row.update(mindlin=wm, rel_error_vs_mindlin=(w - wm) / wm)
                    rows.append(row)
                    if verbose:
                        rs = "" if r is None else f"{r:6.2f}"
                        rm = row.get("rel_error_vs_mindlin")
                        ms = "" if rm is None else f"   vs Mindlin {rm:+.3e}"
                        print(f"{support:8s} {kind:5s} {ah:6.0f} {n:3d} {w:14.8f} {err:+10.3e} {rs:>6s}{ms}")
                    prev = err
    return rows


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ax, support in zip(axes, ("clamped", "ss_hard", "ss_soft")):
        for kind, mk in (("quad", "o"), ("quad~", "D"), ("tri", "^"), ("trix", "s")):
            for ah, ls in ((100.0, "-"), (1000.0, "--")):
                sel = [r for r in rows if r["support"] == support and r["mesh"] == kind and r["a_over_h"] == ah]
                if not sel:
                    continue
                ax.loglog([A / r["n"] for r in sel], [max(abs(r["rel_error"]), 1e-16) for r in sel], ls, marker=mk,
                          label=f"{kind}, a/h={ah:.0f}")
        hh = np.array([A / 4, A / 32])
        ax.loglog(hh, 0.3 * (hh / hh[0]) ** 2, "k:", label="O(h^2)")
        ax.axhline(0.01, color="grey", lw=0.5)
        ax.set_title(support)
        ax.set_xticks([1 / 32, 1 / 16, 1 / 8, 1 / 4])
        ax.set_xticklabels(["1/32", "1/16", "1/8", "1/4"])
        ax.minorticks_off()
        ax.set_xlabel("element size / a")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("|relative error of w_c| vs Kirchhoff series")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description="square plate vs Kirchhoff series")
    ap.add_argument("--quick", action="store_true", help="N = 4, 8, 16 only")
    args = ap.parse_args(argv)
    ns = (4, 8, 16) if args.quick else (4, 8, 16, 32)
    rows = run(ns=ns)
    mitc3 = triangle_vs_mitc3(ns=ns)
    buck = []
    print("Buckling of the SS square plate under uniaxial compression, k = N_cr a^2/(pi^2 D), a/h = 100:")
    for kind in ("quad", "tri"):
        for n in (4, 8, 16):
            b = plate_buckling(n, kind)
            buck.append(b)
            print(f"  {kind:5s} N={n:3d}  k = " + ", ".join(f"{v:.4f}" for v in b["k"]) + "  rel.err "
                  + ", ".join(f"{e:+.2e}" for e in b["rel_error"]) + "  (ref 4, 6.25, 11.11)")
    p = write_json("plates", {"description": __doc__.splitlines()[0], "nu": NU, "a": A, "rows": rows,
                              "triangle_vs_independent_mitc3": mitc3, "buckling": buck})
    OUT.mkdir(exist_ok=True)
    plot(rows, OUT / "plates.png")
    print("wrote", p, "and", OUT / "plates.png")
    bad = [r for r in rows if r["n"] == 32 and r["mesh"] in ("quad", "quad~") and r["support"] != "ss_soft"
           and abs(r["rel_error"]) > 0.01]
    print("32x32 quads within 1%:", "yes" if not bad else f"NO ({len(bad)} cases)")
    return rows


if __name__ == "__main__":
    main()
