"""Independent check that a run's sheet does not pass through itself, from its written files.

    .venv/bin/python -m verification.self_check RUN_DIR [RUN_DIR ...]

Reads ``RUN_DIR/result.vtu`` (meshio: the undeformed nodes, the quad / triangle blocks, the
``displacement`` point data) and ``RUN_DIR/summary.json``, and counts the pairs of mid-surface
triangles (each quad split along its 0-2 diagonal, as solidshell.layers does) that share no node
and intersect: a pair intersects exactly when an edge of one crosses the other.  Its own geometry,
not solidshell's nor the IPC Toolkit's: candidate pairs from a k-d tree on the triangles' centroids
(scipy.spatial.cKDTree, radius 2 r with r the largest distance of a triangle's corner from its
centroid: two triangles whose centroids lie farther apart than that cannot meet), each tested segment against triangle by Moller-Trumbore in numpy.

One line per run; exit 0 when no run passes through itself and every summary that states
``self_intersections`` states this count, 1 otherwise, 2 for unreadable input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .penetration_check import BadInput, read_run


def triangles(quads: np.ndarray, tris: np.ndarray) -> np.ndarray:
    return np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]], tris]).astype(np.int64)


def segment_hits(p, q, a, b, c) -> np.ndarray:
    """(M,) whether the segments p-q cross the triangles a-b-c (all (M, 3))."""
    d, e1, e2, t0 = q - p, b - a, c - a, p - a
    s = np.cross(d, e2)
    r = np.cross(t0, e1)
    det = np.einsum("ij,ij->i", e1, s)
    # a segment (nearly) in the triangle's plane does not cross it: coplanar touching, e.g. clamped
    # edges on one line, is not an intersection (relative 1e-12: round-off of the triple product)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    det = np.where(ok, det, 1.0)
    u = np.einsum("ij,ij->i", t0, s) / det
    v = np.einsum("ij,ij->i", d, r) / det
    t = np.einsum("ij,ij->i", e2, r) / det
    return ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t >= 0.0) & (t <= 1.0)


def intersecting_pairs(x: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(K, 2) the intersecting pairs i < j of triangles F (T, 3) at the positions x that share no node."""
    from scipy.spatial import cKDTree

    P = x[F]  # (T, 3, 3)
    cen = P.mean(axis=1)
    rad = float(np.max(np.linalg.norm(P - cen[:, None], axis=2)))  # every point within rad of its centroid
    pairs = cKDTree(cen).query_pairs(2.0 * rad, output_type="ndarray")
    if not len(pairs):
        return np.zeros((0, 2), np.int64)
    i, j = pairs[:, 0], pairs[:, 1]
    apart = ~(F[i][:, :, None] == F[j][:, None, :]).any(axis=(1, 2))
    i, j = i[apart], j[apart]
    hit = np.zeros(len(i), dtype=bool)
    for a, b in ((i, j), (j, i)):
        for k in range(3):
            hit |= segment_hits(x[F[a, k]], x[F[a, (k + 1) % 3]], x[F[b, 0]], x[F[b, 1]], x[F[b, 2]])
    out = np.column_stack([np.minimum(i, j), np.maximum(i, j)])[hit]
    return out[np.lexsort(out.T[::-1])]


def check_run(run_dir: Path) -> tuple[str, bool]:
    summary, X, D, quads, tris = read_run(run_dir)
    n = len(intersecting_pairs(X + D[:, :3], triangles(quads, tris)))
    said = summary.get("self_intersections")
    agree = "" if said is None else ("  [summary agrees]" if said == n else f"  [MISMATCH: summary says {said}]")
    ok = n == 0 and (said is None or said == n)
    gap = summary.get("min_layer_gap")
    g = "" if gap is None else f", summary's min layer gap {gap:.4g}"
    return f"{run_dir}: {n} intersecting triangle pairs{g}{agree}  " + ("clean" if n == 0 else "THROUGH ITSELF"), ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m verification.self_check", description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=Path, metavar="RUN_DIR")
    a = ap.parse_args(argv)
    ok = True
    for run in a.runs:
        try:
            line, clean = check_run(run)
        except BadInput as e:
            print(f"self_check: {e}", file=sys.stderr)
            return 2
        print(line)
        ok = ok and clean
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
