"""DK against linear transfer of newly inserted nodes (paper §5.4; issue 10, "What it must show").

A coarse mesh is bent to static equilibrium with the existing solvers, every element is then split
1-to-4 and the new mid-edge and centre nodes get their state from the discrete-Kirchhoff transfer
(solidshell.adapt.transfer, Eqs. 27-34; the default stretch-preserving director and the literal
Eq. 32 one) or from linear interpolation.  Measured right after the insertion:

(a) the out-of-balance force |P - F|_free / |P|_free and its largest nodal value / the largest nodal
    load (the coarse state is in balance to the static solver's tolerance, so this is what the
    insertion adds, together with the unavoidable fine-vs-coarse discretisation difference, which
    a perfect transfer would still show);
(b) the kinetic energy that follows: an explicit run (solidshell.solvers.explicit.run, Eq. 23, the
    paper's alpha = 5 1/s, physical masses, zero initial velocity) from each transferred state; the
    peak kinetic energy over the first T ms relative to the strain energy of the state.

    python -m verification.adapt_transfer        (about a minute; writes out/adapt_transfer.md/.json)

The refined meshes are built here by a plain 1-to-4 split (``refine``), with the background-mesh
attribute names of notes/adapt_interface.md (Xo, Xn, conn[l], node_level, mid_parent,
centre_parent); when solidshell.adapt.background lands, the lead switches this study (and the
tests that borrow ``refine``) to BackgroundMesh.from_level0.
"""

from __future__ import annotations

import json
import time
from types import SimpleNamespace

import numpy as np

from solidshell.mesh import ShellMesh

from . import OUT


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _split_once(Xo, Xn, quads, sets):
    """One uniform 1-to-4 split of quads (M,4): child k of element e is 4e+k = [c_k, m_k, centre,
    m_(k-1)] (ccw, first node the parent's node k, Fig. 15).  New nodes are appended: the unique
    edge mid-points (ends averaged, directors averaged and normalised, §5.1), then one centre per
    element (8-node serendipity at the centre, §5.1).  Returns (Xo, Xn, fine quads, mid_parent rows
    [A,B,E] and centre_parent rows [c0..c3, m0..m3] of the new nodes, node sets)."""
    N, M = len(Xo), len(quads)
    e = np.stack([quads, np.roll(quads, -1, axis=1)], axis=-1).reshape(-1, 2)   # edge k of e: 4e+k
    _, first, inv = np.unique(np.sort(e, axis=1), axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    A, B = e[first, 0], e[first, 1]
    E = quads[first // 4, (first % 4 + 2) % 4]
    mid = (N + inv).reshape(M, 4)
    cen = N + len(first) + np.arange(M)
    Xo_m, Xn_m = 0.5 * (Xo[A] + Xo[B]), _unit(Xn[A] + Xn[B])
    Xo_all = np.concatenate([Xo, Xo_m])
    Xn_all = np.concatenate([Xn, Xn_m])
    ser = lambda X: -0.25 * X[quads].sum(1) + 0.5 * X[mid].sum(1)
    Xo_all = np.concatenate([Xo_all, ser(Xo_all)])
    Xn_all = np.concatenate([Xn_all, _unit(ser(Xn_all))])
    fine = np.stack([quads, mid, np.repeat(cen[:, None], 4, 1), np.roll(mid, 1, axis=1)],
                    axis=-1).reshape(-1, 4)
    new_sets = {}
    for name, idx in sets.items():
        inside = np.zeros(len(Xo_all), bool)
        inside[idx] = True
        m_in = inside[A] & inside[B]
        c_in = inside[quads].all(1)
        new_sets[name] = np.concatenate([idx, N + np.flatnonzero(m_in), cen[c_in]])
    return (Xo_all, Xn_all, fine, np.column_stack([A, B, E]),
            np.column_stack([quads, mid]), new_sets)


def refine(mesh: ShellMesh, levels: int = 1):
    """(background, fine ShellMesh): ``levels`` uniform 1-to-4 splits of a quad mesh.  The background
    carries the attribute names of the adaptive interface: Xo, Xn (Nb,3), levels, n0, conn[l],
    node_level (Nb,), mid_parent (Nb,3) [A,B,E] and centre_parent (Nb,8) (-1 rows elsewhere).  The
    fine mesh is the finest level, with inherited node sets (a mid-edge node is in a set when both
    edge ends are, a centre when all four corners are)."""
    Xo, Xn = mesh.nodes.copy(), mesh.directors.copy()
    conn = [mesh.quads.copy()]
    node_level = np.zeros(len(Xo), dtype=np.int64)
    mid_rows, cen_rows = [np.full((len(Xo), 3), -1)], [np.full((len(Xo), 8), -1)]
    sets = dict(mesh.node_sets)
    for l in range(levels):
        N = len(Xo)
        Xo, Xn, fine, mp, cp, sets = _split_once(Xo, Xn, conn[-1], sets)
        n_mid, n_cen = len(mp), len(cp)
        node_level = np.concatenate([node_level, np.full(n_mid + n_cen, l + 1)])
        mid_rows += [mp, np.full((n_cen, 3), -1)]
        cen_rows += [np.full((n_mid, 8), -1), cp]
        assert len(Xo) == N + n_mid + n_cen
        conn.append(fine)
    bg = SimpleNamespace(Xo=Xo, Xn=Xn, levels=levels, n0=len(mesh.quads), conn=conn,
                         node_level=node_level, mid_parent=np.concatenate(mid_rows),
                         centre_parent=np.concatenate(cen_rows))
    return bg, ShellMesh(Xo, quads=conn[-1], directors=Xn, node_sets=sets)
