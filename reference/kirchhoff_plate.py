"""Independent references for a square Kirchhoff plate under uniform pressure (small deflection).

Centre deflection w_c = alpha * q a^4 / D, D = E h^3 / (12 (1 - nu^2)), nu = 0.3 (alpha of a Kirchhoff
plate does not depend on nu for these two support cases; nu only enters through D).

What this script computes (nothing here uses solidshell):

1. Simply supported (Navier, hard support w = 0, M_nn = 0):
   * the Navier double series, summed over odd m, n <= N until the partial sums stop changing;
   * the Levy single series (Timoshenko & Woinowsky-Krieger, Theory of Plates and Shells, 2nd ed.,
     1959, Sect. 30, Eq. (c)-(d)), which converges like m^-5 times an exponentially decaying factor.
   Published: alpha = 0.00406 (T&W-K Table 8, b/a = 1).
2. Clamped (w = dw/dn = 0):
   * the superposition method of T&W-K Sect. 44 (Hencky's method): the simply supported plate under q
     plus two pairs of Levy solutions loaded by symmetric edge moments M = sum_m E_m sin(m pi s/a) on
     the four edges; the coefficients E_m follow from the condition of zero edge slope, an infinite
     linear system that is truncated at M terms and solved; the centre deflection converges with M.
   Published: alpha = 0.00126 (T&W-K Table 35, b/a = 1); 0.00126532 (Taylor & Govindjee 2004,
   Int. J. Numer. Meth. Biomed. Eng. 20:757, "Solution of clamped rectangular plate problems").
3. A different discretisation (scikit-fem): the nonconforming Morley triangle (quadratic) and the
   conforming C1 Argyris triangle (quintic) for D nabla^4 w = q on (0,1)^2, symmetric ("union
   jack") meshes refined uniformly; the centre is a mesh vertex, w_c is its nodal value.  Boundary
   conditions as in skfem's example ex02: clamped = every boundary dof; simply supported = the
   dofs that vanish when w = 0 along the edge (w and its tangential derivatives).

Run ``python reference/kirchhoff_plate.py`` (about 3 CPU-minutes, mostly the finest Morley mesh) to regenerate
``reference/plates.json``; ``--quick`` skips the finest meshes.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import platform
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
NU = 0.3

PUBLISHED = {
    "simply_supported": {"alpha": 0.00406, "source": "Timoshenko & Woinowsky-Krieger (1959), Table 8, b/a=1"},
    "clamped": {"alpha": 0.00126, "source": "Timoshenko & Woinowsky-Krieger (1959), Table 35, b/a=1"},
    "clamped_8_digits": {
        "alpha": 0.00126532,
        "source": "Taylor & Govindjee (2004), Commun. Numer. Meth. Engng 20:757-765",
    },
    "simply_supported_8_digits": {
        "alpha": 0.00406235,
        "source": "Navier/Levy series (quoted widely, e.g. Taylor & Govindjee 2004)",
    },
}


# --------------------------------------------------------------------------- series solutions
def navier_ss_alpha(n_terms: int) -> float:
    """Navier double series at the centre, odd m, n <= n_terms:
    alpha = 16/pi^6 sum_{m,n odd} (-1)^((m+n)/2 - 1) / (m n (m^2 + n^2)^2)."""
    m = np.arange(1, n_terms + 1, 2, dtype=float)
    M, N = np.meshgrid(m, m, indexing="ij")
    sgn = (-1.0) ** ((M + N) / 2 - 1)
    return float(16.0 / math.pi**6 * np.sum(sgn / (M * N * (M**2 + N**2) ** 2)))


def marcus_moment_centre(n_terms: int) -> float:
    """Marcus moment sum M = (M_x + M_y)/(1 + nu) at the centre of the SS square, in q a^2:
    nabla^2 M = -q, M = 0 on the edges: 16/pi^4 sum_{m,n odd} (-1)^((m+n)/2-1) / (m n (m^2 + n^2)).
    A hard simply supported Reissner-Mindlin plate deflects w = w_Kirchhoff + M/(kappa G h), so at the
    centre w_c D/(q a^4) = alpha + c (h/a)^2, see mindlin_ss_shear_coefficient."""
    m = np.arange(1, n_terms + 1, 2, dtype=float)
    M, N = np.meshgrid(m, m, indexing="ij")
    sgn = (-1.0) ** ((M + N) / 2 - 1)
    return float(16.0 / math.pi**4 * np.sum(sgn / (M * N * (M**2 + N**2))))


def mindlin_ss_shear_coefficient(nu: float = NU, kappa: float = 5.0 / 6.0, n_terms: int = 4001) -> float:
    """c in w_c D/(q a^4) = alpha_SS + c (h/a)^2 for the hard SS Reissner-Mindlin square plate:
    D/(kappa G h) = h^2 / (6 kappa (1 - nu)), so c = M_c / (6 kappa (1 - nu))."""
    return marcus_moment_centre(n_terms) / (6.0 * kappa * (1.0 - nu))


def levy_ss_alpha(n_terms: int) -> float:
    """Levy single series (T&W-K Sect. 30) for the square, centre:
    alpha = 5/384 - 4/pi^5 sum_{m odd} (-1)^((m-1)/2) / m^5 * (a_m tanh a_m + 2) / (2 cosh a_m),
    a_m = m pi / 2."""
    s = 0.0
    for m in range(1, n_terms + 1, 2):
        am = m * math.pi / 2
        s += (-1) ** ((m - 1) // 2) / m**5 * (am * math.tanh(am) + 2.0) / (2.0 * math.cosh(am))
    return 5.0 / 384.0 - 4.0 / math.pi**5 * s


@functools.lru_cache(maxsize=4)
def _gauss_legendre(n: int):
    # numpy's leggauss solves an n x n eigenproblem: cache it (it dominates the run time otherwise)
    return np.polynomial.legendre.leggauss(n)


def clamped_superposition_alpha(n_terms: int, n_quad: int = 2000) -> float:
    """Clamped square plate (a = 1, D = 1, q = 1), superposition of T&W-K Sect. 44.

    Plate [0,a]^2.  w = w0 + w1 + w2:
      w0: simply supported plate under q (Levy series in sin(alpha_m x), alpha_m = m pi / a);
      w1: sum_m E_m sin(alpha_m x) Y_m(y - a/2), w = 0 on all edges, moment E_m sin(alpha_m x) on
          y = 0 and y = a, none on x = 0, a;
      w2: the same rotated by 90 degrees (same E_m by the symmetry of the square).
    Zero slope dw/dy on y = a, expanded in sin(alpha_m x) for odd m <= n_terms, gives the system.
    """
    a = 1.0
    ms = np.arange(1, n_terms + 1, 2)
    al = ms * math.pi / a
    beta = al * a / 2
    # Gauss-Legendre on [0, a] for the cross-expansion coefficients
    xg, wg = _gauss_legendre(n_quad)
    x = 0.5 * a * (xg + 1.0)
    w = 0.5 * a * wg
    xi = x - a / 2

    def ratio_cosh(arg, b):  # cosh(arg)/cosh(b), |arg| <= b, overflow-safe
        return np.exp(np.abs(arg) - b) * (1 + np.exp(-2 * np.abs(arg))) / (1 + np.exp(-2 * b))

    def ratio_sinh(arg, b):  # sinh(arg)/cosh(b)
        return np.sign(arg) * np.exp(np.abs(arg) - b) * (1 - np.exp(-2 * np.abs(arg))) / (1 + np.exp(-2 * b))

    # w0 slope on y = a: Levy particular Yp = 4 q /(m pi D alpha^4), homogeneous with Y = Y'' = 0 at edges
    Yp = 4.0 / (ms * math.pi * al**4)
    B0 = Yp / 2.0  # B cosh(beta)
    A0 = -Yp - B0 * beta * np.tanh(beta)  # A cosh(beta)
    # Y'(a/2) = alpha [A sinh b + B (sinh b + b cosh b)] / with cosh scaling removed
    slope0 = al * (A0 * np.tanh(beta) + B0 * (np.tanh(beta) + beta))
    w0c = np.sum(np.sin(al * a / 2) * (Yp + A0 / np.cosh(beta)))  # centre: Y(0) = Yp + A
    # w1 per unit E_m: slope at y = a (eta = a/2)
    Ap = -(-1.0 / (2 * al**2)) * beta * np.tanh(beta)
    Bp = -1.0 / (2 * al**2)
    slope1 = al * (Ap * np.tanh(beta) + Bp * (np.tanh(beta) + beta))
    w1c = np.sin(al * a / 2) * Ap / np.cosh(beta)  # centre value per unit E_m
    # w2 per unit E_n: dw2/dy at y = a = alpha_n cos(alpha_n a) X_n(x - a/2), expanded in sin(alpha_m x)
    Xn = Ap[None, :] * ratio_cosh(al[None, :] * xi[:, None], beta[None, :]) + Bp[None, :] * al[None, :] * xi[
        :, None
    ] * ratio_sinh(al[None, :] * xi[:, None], beta[None, :])
    g = (al * np.cos(al * a))[None, :] * Xn  # (q, n)
    S = np.sin(np.outer(x, al))  # (q, m)
    C = (2.0 / a) * (S * w[:, None]).T @ g  # C[m, n]
    Amat = np.diag(slope1) + C
    E = np.linalg.solve(Amat, -slope0)
    return float(w0c + 2.0 * np.sum(w1c * E))


# --------------------------------------------------------------------------- scikit-fem solves
def skfem_plate(element: str, support: str, refine: int) -> dict:
    """Centre deflection of D nabla^4 w = q on (0,1)^2, D = 1, q = 1, nu = 0.3 (scikit-fem)."""
    from skfem import Basis, BilinearForm, ElementTriArgyris, ElementTriMorley, MeshTri, asm, condense, solve
    from skfem.helpers import dd, ddot, eye, trace
    from skfem.models.poisson import unit_load

    m = (
        MeshTri.init_symmetric()
        .refined(refine)
        .with_boundaries(
            {
                "xedge": lambda x: (np.abs(x[0]) < 1e-12) | (np.abs(x[0] - 1) < 1e-12),
                "yedge": lambda x: (np.abs(x[1]) < 1e-12) | (np.abs(x[1] - 1) < 1e-12),
            }
        )
    )
    el = {"morley": ElementTriMorley, "argyris": ElementTriArgyris}[element]()
    intorder = 4 if element == "morley" else 10
    ib = Basis(m, el, intorder=intorder)

    @BilinearForm
    def bilinf(u, v, w):
        # M = D [(1-nu) K + nu tr(K) I] with D = 1: the plane-stress plate of skfem's ex02
        def C(T):
            return (1 - NU) * T + NU * eye(trace(T), 2)

        return ddot(C(dd(u)), dd(v))

    K = asm(bilinf, ib)
    f = asm(unit_load, ib)
    if element == "morley":
        names_x = names_y = ["u", "u_n"] if support == "clamped" else ["u"]
    else:
        if support == "clamped":
            names_x = ["u", "u_x", "u_y", "u_xy", "u_yy", "u_n"]  # w = w_n = 0 along x = const
            names_y = ["u", "u_x", "u_y", "u_xy", "u_xx", "u_n"]
        else:
            names_x = ["u", "u_y", "u_yy"]  # w = 0 along x = const
            names_y = ["u", "u_x", "u_xx"]
    Dof = np.unique(np.concatenate([ib.get_dofs("xedge").all(names_x), ib.get_dofs("yedge").all(names_y)]))
    x = solve(*condense(K, f, D=Dof))
    ic = int(np.argmin(np.sum((m.p - 0.5) ** 2, axis=0)))
    assert np.allclose(m.p[:, ic], 0.5)
    wc = float(x[ib.nodal_dofs[0, ic]])
    return {
        "element": element,
        "support": support,
        "refine": refine,
        "n_triangles": int(m.t.shape[1]),
        "h": float(1.0 / 2**refine),
        "n_dofs": int(K.shape[0]),
        "alpha": wc,
    }


def convergence_table(element, support, refines, exact):
    rows = []
    for r in refines:
        t0 = time.perf_counter()
        row = skfem_plate(element, support, r)
        row["seconds"] = round(time.perf_counter() - t0, 3)
        row["rel_error"] = (row["alpha"] - exact) / exact
        if rows and rows[-1]["rel_error"] != 0 and row["rel_error"] != 0:
            row["rate"] = math.log(abs(rows[-1]["rel_error"] / row["rel_error"])) / math.log(2.0)
        else:
            row["rate"] = None
        rows.append(row)
        print(
            f"  {element:8s} {support:16s} refine {r}  tris {row['n_triangles']:6d}  dofs {row['n_dofs']:7d}  "
            f"alpha {row['alpha']:.9f}  rel.err {row['rel_error']:+.3e}  rate {row['rate'] if row['rate'] is None else round(row['rate'], 2)}"
        )
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the finest meshes")
    ap.add_argument("--out", default=str(HERE / "plates.json"))
    args = ap.parse_args(argv)

    print("Series solutions (alpha = w_c D / (q a^4))")
    navier = {n: navier_ss_alpha(n) for n in (11, 51, 201, 801, 2001)}
    levy = {n: levy_ss_alpha(n) for n in (1, 3, 5, 11, 21)}
    for n, v in navier.items():
        print(f"  SS Navier, odd m,n <= {n:5d}: {v:.10f}")
    for n, v in levy.items():
        print(f"  SS Levy,   odd m   <= {n:5d}: {v:.10f}")
    clamped = {n: clamped_superposition_alpha(n) for n in (5, 11, 21, 41, 81, 161)}
    for n, v in clamped.items():
        print(f"  clamped superposition, odd m <= {n:4d}: {v:.10f}")
    ss_alpha = levy[21]
    cl_alpha = clamped[161]

    mor_ref = (2, 3, 4, 5, 6) if args.quick else (2, 3, 4, 5, 6, 7)
    arg_ref = (1, 2, 3, 4) if args.quick else (1, 2, 3, 4, 5)
    print("scikit-fem Morley / Argyris, union-jack meshes, h = 1/2^refine")
    tables = {}
    for support, exact in (("simply_supported", ss_alpha), ("clamped", cl_alpha)):
        tables[f"morley_{support}"] = convergence_table("morley", support, mor_ref, exact)
        tables[f"argyris_{support}"] = convergence_table("argyris", support, arg_ref, exact)

    out = {
        "description": "Square Kirchhoff plate, uniform pressure q, centre deflection w_c = alpha q a^4 / D, nu = 0.3",
        "generated_by": "python reference/kirchhoff_plate.py" + (" --quick" if args.quick else ""),
        "python": platform.python_version(),
        "alpha": {"simply_supported": ss_alpha, "clamped": cl_alpha},
        "alpha_sources": {
            "simply_supported": "Levy single series, odd m <= 21 (agrees with the Navier double series to 1e-12)",
            "clamped": "superposition (Hencky / T&W-K Sect. 44), odd m <= 161, truncation converged",
        },
        "series": {
            "navier_ss": {str(k): v for k, v in navier.items()},
            "levy_ss": {str(k): v for k, v in levy.items()},
            "clamped_superposition": {str(k): v for k, v in clamped.items()},
        },
        "published": PUBLISHED,
        "marcus_moment_centre": marcus_moment_centre(4001),
        "mindlin_ss_shear_coefficient": mindlin_ss_shear_coefficient(),
        "mindlin_note": (
            "hard simply supported Reissner-Mindlin plate, kappa = 5/6: "
            "w_c D/(q a^4) = alpha_SS + mindlin_ss_shear_coefficient * (h/a)^2"
        ),
        "skfem": tables,
        "morley_richardson": {
            sup: (4 * tables[f"morley_{sup}"][-1]["alpha"] - tables[f"morley_{sup}"][-2]["alpha"]) / 3
            for sup in ("simply_supported", "clamped")
        },
        "note": (
            "Argyris errors below ~1e-8 are round-off of the direct solve (they stop decreasing at "
            "refine 4-5); the series values are converged to ~1e-12 relative."
        ),
    }
    for sup, v in out["morley_richardson"].items():
        print(f"  Morley Richardson (h^2) extrapolation, {sup}: {v:.9f}")
    Path(args.out).write_text(json.dumps(out, indent=1))
    print("wrote", args.out)
    return out


if __name__ == "__main__":
    main()
