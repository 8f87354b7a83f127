"""Element evaluations per second of the batched kernels (issue 3 speed figures).

Usage: python benchmarks/element_throughput.py [--elements 10000] [--repeats 7]

Measures, for quads and for triangles on a randomly deformed flat sheet: the internal force kernel
(energy + force, the explicit solver's hot path), the force + tangent kernel, and the whole
Model.force_and_tangent including CSR assembly.  Numba's first-call (compile or cache load) time is
reported separately; figures are medians over repeats.  Compare figures within one run: the machine
is shared.  For the quadrilateral with the compatible membrane the lane kernel of the explicit
solver (elements/lanes.py, elements in SIMD lanes) is timed beside core.energy_force, interleaved,
with the ratio, its flop rate (lanes.FLOPS_PER_ELEMENT) and the largest relative force difference;
the triangle the same way with its lane kernel (elements/lanes_tri.py).
The assumed-membrane quadrilateral (membrane="ans") is timed the same way on the same sheet: its
lane kernel (elements/lanes_ans.py) beside the full lane kernel, core.energy_force on its compact
10-tie form and on the dense 26-tie form it had before the factorisation (quad4.dense_membrane),
interleaved, with the force differences and the ratios to the full lane kernel.
``--passes 2`` runs everything twice; the load average is printed with each pass.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from numba import get_num_threads

from solidshell import IsotropicShell, ShellMesh
from solidshell.elements import core, lanes, lanes_ans, lanes_tri, quad4
from solidshell.model import Model


def sheet(n: int, tri: bool) -> ShellMesh:
    x = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(x, x)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    if tri:
        return ShellMesh(P, tris=np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]), check=False)
    return ShellMesh(P, quads=q, check=False)


def median_time(fn, repeats: int) -> float:
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, default=10000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument(
        "--membrane",
        default="full,ans",
        help="quadrilateral membrane variants to measure (solidshell/elements/quad4.py)",
    )
    ap.add_argument("--passes", type=int, default=1)
    args = ap.parse_args(argv)
    for p in range(args.passes):
        print(f"pass {p + 1}: numba threads {get_num_threads()}, load average {os.getloadavg()}", flush=True)
        one_pass(args)


def lane_comparison(mesh, model, U, repeats, mod=lanes):
    """core.energy_force vs the lane kernel of ``mod`` (lanes: quad_forces, lanes_tri: tri_forces)
    on the same elements, interleaved (wall and CPU medians)."""
    b = model.blocks[0]
    M, nn = b.conn.shape
    xo, xn, Uc = model._current(U)
    fe, we = np.empty((M, nn, 6)), np.empty(M)
    pk = mod.pack(b.conn, b.c, b.c["r_zq"])
    L = lanes.LANES
    xs, fs, ws = np.empty((pk["B"], 12 * nn * L)), np.empty((pk["B"], 6 * nn * L)), np.empty((pk["B"], L))
    nth = get_num_threads()
    kernel = lanes_tri.tri_forces if mod is lanes_tri else mod.quad_forces

    def old():
        return core.energy_force(*b.args(xo, xn, Uc, False, 0.5), fe, we, nth)

    def new():
        return kernel(
            mesh.nodes, mesh.directors, Uc, pk["conn"], pk["Cmb"], pk["Cs"], pk["Cz"], pk["r_z"], False, 0.5, xs, fs, ws
        )

    old()
    new()
    t = {"core": [], "lanes": []}
    c = {"core": [], "lanes": []}
    for _ in range(repeats):
        for k, fn in (("core", old), ("lanes", new)):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            t[k].append(time.perf_counter() - t0)
            c[k].append(time.process_time() - c0)
    diff = np.abs(mod.unpack_forces(fs, M) - fe).max() / np.abs(fe).max()
    for k in t:
        tw, tc = float(np.median(t[k])), float(np.median(c[k]))
        print(
            f"  {k:5s} force kernel   {M / tw / 1e6:8.3f} M elem/s wall, {M / tc / 1e6:6.3f} M elem/s per CPU-s"
            + (f", {mod.FLOPS_PER_ELEMENT * M / tw / 1e9:5.2f} GFLOP/s wall" if k == "lanes" else "")
        )
    print(
        f"  lanes / core: {np.median(t['core']) / np.median(t['lanes']):.2f} (wall), "
        f"{np.median(c['core']) / np.median(c['lanes']):.2f} (CPU); max |f_lanes - f_core| / max |f| = {diff:.1e}"
    )


def interleaved(fns, repeats):
    """{name: (wall median, CPU median)} of the callables ``fns`` {name: fn}, one call of each in
    turn per repeat (so a change of machine load falls on all of them alike)."""
    for fn in fns.values():
        fn()
    t = {k: [] for k in fns}
    c = {k: [] for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            t[k].append(time.perf_counter() - t0)
            c[k].append(time.process_time() - c0)
    return {k: (float(np.median(t[k])), float(np.median(c[k]))) for k in fns}


def ans_comparison(mesh, U, repeats):
    """The membrane="ans" quad: lane kernel, core on the compact (10 ties) and on the dense (26
    ties) form, beside the full lane kernel, interleaved, on the same sheet and displacements."""
    sec = IsotropicShell(E=1e5, nu=0.3, h=0.01)
    full, ans = Model(mesh, sec, membrane="full"), Model(mesh, sec, membrane="ans")
    bf, ba = full.blocks[0], ans.blocks[0]
    M = len(ba.conn)
    xo, xn, Uc = ans._current(U)
    L = lanes.LANES
    out = {}

    def lane_call(mod, b):
        pk = mod.pack(b.conn, b.c, b.c["r_zq"])
        xs, fs, ws = np.empty((pk["B"], 48 * L)), np.empty((pk["B"], 24 * L)), np.empty((pk["B"], L))
        out[mod.__name__] = fs
        return lambda: mod.quad_forces(
            mesh.nodes, mesh.directors, Uc, pk["conn"], pk["Cmb"], pk["Cs"], pk["Cz"], pk["r_z"], False, 0.5, xs, fs, ws
        )

    args = ba.args(xo, xn, Uc, False, 0.5)
    Cs = np.zeros((M, 26, 26))
    Cs[:, :4, :4] = ba.c["Cs"][:, :4, :4]
    Cs[:, 4:, 4:] = quad4.dense_membrane(mesh.nodes[ba.conn], ba.c, sec.C_m)
    dense = (
        args[:5]
        + (
            np.vstack([quad4.ALPHA, quad4.M_ALPHA]),
            np.vstack([quad4.BETA, quad4.M_BETA]),
            np.vstack([quad4.TIE, quad4.M_TIE]),
            args[8],
            Cs,
        )
        + args[10:]
    )
    fc, fd, w = np.empty((M, 4, 6)), np.empty((M, 4, 6)), np.empty(M)
    nth = get_num_threads()
    fns = {
        "full lanes": lane_call(lanes, bf),
        "ans lanes": lane_call(lanes_ans, ba),
        "ans core": lambda: core.energy_force(*args, fc, w, nth),
        "ans core dense": lambda: core.energy_force(*dense, fd, w, nth),
    }
    res = interleaved(fns, repeats)
    flops = {"full lanes": lanes.FLOPS_PER_ELEMENT, "ans lanes": lanes_ans.FLOPS_PER_ELEMENT}
    print(f"quad4 M={M:6d}: membrane=ans force kernels beside the full lane kernel (interleaved)")
    for k, (tw, tc) in res.items():
        print(
            f"  {k:15s} {M / tw / 1e6:8.3f} M elem/s wall, {M / tc / 1e6:6.3f} per CPU-s, "
            f"{tw / res['full lanes'][0]:5.2f} x full lanes' time"
            + (f", {flops[k] * M / tw / 1e9:5.2f} GFLOP/s" if k in flops else "")
        )
    scale = np.abs(fc).max()
    print(
        f"  max |f - f_ans core| / max |f|: ans lanes "
        f"{np.abs(lanes.unpack_forces(out[lanes_ans.__name__], M) - fc).max() / scale:.1e}, "
        f"ans core dense {np.abs(fd - fc).max() / scale:.1e}"
    )
    # the static solver's kernel: force + tangent (core.force_tangent), the three forms
    K = np.empty((M, 24, 24))
    fargs = bf.args(xo, xn, Uc, False, 0.5)
    res = interleaved(
        {
            "full": lambda: core.force_tangent(*fargs, True, fc, w, K, nth),
            "ans": lambda: core.force_tangent(*args, False, fc, w, K, nth),
            "ans dense": lambda: core.force_tangent(*dense, False, fd, w, K, nth),
        },
        repeats,
    )
    print("  force+tangent (core.force_tangent, interleaved):")
    for k, (tw, tc) in res.items():
        print(f"  {k:15s} {M / tw / 1e3:8.1f} k elem/s wall, {tw / res['full'][0]:5.2f} x full's time")


def one_pass(args):
    cases = [(False, m) for m in args.membrane.split(",")] + [(True, "full")]
    for tri, membrane in cases:
        n = int(round(np.sqrt(args.elements / (2 if tri else 1))))
        mesh = sheet(n, tri)
        model = Model(mesh, IsotropicShell(E=1e5, nu=0.3, h=0.01), membrane=membrane)
        U = 0.05 * np.random.default_rng(0).standard_normal((mesh.n_nodes, 6))
        b = model.blocks[0]
        M = len(b.conn)
        xo, xn, Uc = model._current(U)
        fe = np.empty((M, b.nn, 6))
        we = np.empty(M)
        Ke = np.empty((M, 6 * b.nn, 6 * b.nn))
        nth = get_num_threads()
        t0 = time.perf_counter()
        core.energy_force(*b.args(xo, xn, Uc, False, 0.5), fe, we, nth)
        core.force_tangent(*b.args(xo, xn, Uc, False, 0.5), b.gp_membrane, fe, we, Ke, nth)
        model.force_and_tangent(U)
        first = time.perf_counter() - t0
        tf = median_time(lambda: core.energy_force(*b.args(xo, xn, Uc, False, 0.5), fe, we, nth), args.repeats)
        tk = median_time(
            lambda: core.force_tangent(*b.args(xo, xn, Uc, False, 0.5), b.gp_membrane, fe, we, Ke, nth), args.repeats
        )
        tF = median_time(lambda: model.internal_force(U), args.repeats)
        tA = median_time(lambda: model.force_and_tangent(U), args.repeats)
        name = "tri3 " if tri else f"quad4 membrane={membrane}"
        if not tri and membrane == "full":
            print(f"{name} M={M:6d}: lane kernel vs core kernel (interleaved)")
            lane_comparison(mesh, model, U, args.repeats)
        if tri:
            print(f"{name} M={M:6d}: lane kernel vs core kernel (interleaved)")
            lane_comparison(mesh, model, U, args.repeats, lanes_tri)
        if not tri and membrane == "ans":
            ans_comparison(mesh, U, args.repeats)
        print(f"{name} M={M:6d}  first call (compile/cache load) {first:6.2f} s")
        print(f"  force kernel          {M / tf / 1e6:8.3f} M elem/s   ({tf * 1e3:7.2f} ms)")
        print(f"  force+tangent kernel  {M / tk / 1e3:8.1f} k elem/s   ({tk * 1e3:7.2f} ms)")
        print(f"  Model.internal_force  {M / tF / 1e6:8.3f} M elem/s   ({tF * 1e3:7.2f} ms, incl. gather/scatter)")
        print(f"  Model.force_and_tangent {M / tA / 1e3:6.1f} k elem/s   ({tA * 1e3:7.2f} ms, incl. CSR assembly)")


if __name__ == "__main__":
    main()
