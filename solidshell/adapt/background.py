"""Background mesh of the adaptive subdivision (paper Section 5.1, Figs. 14-15).

Every level-0 quadrilateral is split 1-to-4 ``levels`` times.  All nodes of all levels are numbered
once and their initial positions X_o and unit directors X_n stored once [length, -]:

* a mid-edge node is the average of its edge's two end nodes (the director average normalised);
  with ``curves`` a new *boundary* mid-edge node whose edge lies on the curve is projected onto it;
* a centre node is the 8-node serendipity interpolation at the element centre, N_corner = -1/4,
  N_mid = 1/2, of the 4 corners and the 4 mid-edge nodes (director likewise, then normalised).

Element (l, e) of level l has index e in 0..n0*4**l - 1 and children 4e+k, k = 0..3,
counter-clockwise, child k's first node being the parent's node k (Fig. 15):
child k = [c_k, m_k, centre, m_(k-1)] with m_k the mid-edge node of edge k (node k -> node k+1).
So the mid-edge node of edge k of (l, e) is ``conn[l+1][4e+k, 1]`` and its centre ``conn[l+1][4e+k, 2]``.
Labels are the paper's ``i0-c1-c2-...`` with c = k + 1.
"""

from __future__ import annotations

import os
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..mesh import ShellMesh

#: bytes of background-mesh storage (and construction temporaries) per finest-level element:
#: per node (about one per finest element) X_o, X_n 48, node_level 8, mid_parent 24,
#: centre_parent 64; connectivity of all levels 32*4/3, neighbour tables 32/3, leaf flags 4/3;
#: the finest split's edge keys and np.unique work arrays ~ 64 per finest element.
BYTES_PER_FINEST_ELEMENT = 48 + 8 + 24 + 64 + 43 + 11 + 2 + 64
MAX_LEVELS = 12


def estimate_background_bytes(n0_quads: int, levels: int) -> int:
    """Estimated memory [bytes] of the background mesh of ``n0_quads`` level-0 quads split
    ``levels`` times (n0 * 4**levels finest elements, about one node each)."""
    return int(n0_quads) * 4 ** int(levels) * BYTES_PER_FINEST_ELEMENT


def _available_bytes() -> int:
    """Memory the process may still use: MemAvailable of /proc/meminfo, else physical memory."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def circle_projector(centre, radius):
    """A ``curves`` callable for BackgroundMesh: points (K,3) moved radially (in the plane of
    constant z through them) onto the circle of ``radius`` [length] about ``centre`` (x, y[, z]);
    with several radii (concentric circles, e.g. the circular sheet's rim and the disc pedestal's
    rim of circle-pedestal) each point goes to the nearest one.  BackgroundMesh only projects
    mid-edge nodes of boundary edges whose two end nodes already lie on the curve, so straight
    boundary edges (the square sheet's sides) are left alone."""
    c = np.zeros(3)
    c[: len(centre)] = np.asarray(centre, dtype=float)
    radii = np.atleast_1d(np.asarray(radius, dtype=float))
    if radii.ndim != 1 or not radii.size or not np.all(np.isfinite(radii) & (radii > 0.0)):
        raise InputError(f"circle radius must be a positive length (or a list of them), got {radius!r}")

    def project(P):
        P = np.asarray(P, dtype=float)
        d = P[:, :2] - c[:2]
        n = np.linalg.norm(d, axis=1)
        r = radii[np.argmin(np.abs(n[:, None] - radii[None, :]), axis=1)]
        out = P.copy()
        ok = n > 0.0
        out[ok, :2] = c[:2] + d[ok] * (r[ok] / n[ok])[:, None]
        return out

    return project


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _edge_table(C):
    """Unique undirected edges of quads C (m,4): (edges (E,2) sorted pairs, edge id of each
    element side (m,4), number of sides on each edge (E,), first side 4e+k on each edge (E,))."""
    sides = np.stack([C, np.roll(C, -1, axis=1)], axis=2).reshape(-1, 2)
    key = np.sort(sides, axis=1)
    edges, first, inv, cnt = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    return edges, inv.reshape(C.shape), cnt, first


def _neighbours(side_edge, cnt):
    """(m,4) same-level element across each side (-1 on the boundary)."""
    m = len(side_edge)
    flat = side_edge.ravel()
    order = np.argsort(flat, kind="stable")
    owner = np.repeat(np.arange(m), 4)[order]
    se = flat[order]
    # each interior edge appears exactly twice, consecutively after sorting
    nb = np.full(4 * m, -1, dtype=np.int64)
    pair = np.flatnonzero(se[1:] == se[:-1])
    nb[order[pair]] = owner[pair + 1]
    nb[order[pair + 1]] = owner[pair]
    if np.any(cnt > 2):
        raise InputError("the level-0 mesh has an edge shared by more than two quads (non-manifold)")
    return nb.reshape(m, 4)


def _checked_levels(mesh: ShellMesh, levels) -> int:
    """``levels`` as an int after refusing a level-0 mesh with triangles, a level that is not an
    integer >= 0, and a background mesh that would not fit in half the available memory."""
    if len(mesh.tris):
        raise InputError(
            f"adaptivity needs a level-0 mesh of quadrilaterals only; this one has "
            f"{len(mesh.tris)} triangle(s) (only quadrilateral level-0 meshes are supported)"
        )
    try:
        levels_i = int(levels)
    except (TypeError, ValueError):
        raise InputError(f"adapt levels must be an integer >= 0, got {levels!r}") from None
    if levels_i != levels or levels_i < 0:
        raise InputError(f"adapt levels must be an integer >= 0, got {levels!r}")
    n0 = len(mesh.quads)
    est = estimate_background_bytes(n0, levels_i)
    avail = _available_bytes()
    if levels_i > MAX_LEVELS or est > avail // 2:
        raise InputError(
            f"adapt levels = {levels_i} on {n0} level-0 quads needs a background mesh of "
            f"{n0 * 4**levels_i:.3g} elements, about {est / 2**30:.3g} GiB, more than half "
            f"the {avail / 2**30:.3g} GiB available; use fewer levels"
        )
    return levels_i


class _Split(NamedTuple):
    """One 1-to-4 split of a level (:func:`_split_level`); new nodes: the ne mid-edge ones, then the m centres."""

    nbr: np.ndarray  # (m,4) same-level element across each side of the split level (-1 on the boundary)
    XM: np.ndarray  # (ne,3) mid-edge node positions
    DM: np.ndarray  # (ne,3) mid-edge node directors
    XC: np.ndarray  # (m,3) centre node positions
    DC: np.ndarray  # (m,3) centre node directors
    mid_parent: np.ndarray  # (ne+m,3) [A, B, E] of the mid-edge nodes, -1 for the centres
    centre_parent: np.ndarray  # (ne+m,8) 4 corners and 4 mid-edge nodes of the centres, -1 for the mids
    children: np.ndarray  # (4m,4) connectivity of the next level


def _split_level(C, Xall, Dall, N: int, curves, L: float) -> _Split:
    """Split the quads C (m,4) of one level, whose nodes are Xall, Dall (N,3), 1-to-4 (module
    docstring); the new nodes are numbered from N.  ``curves``: boundary projection (within 1e-9 L)."""
    m = len(C)
    edges, side_edge, cnt, first_side = _edge_table(C)
    nbr = _neighbours(side_edge, cnt)
    ne = len(edges)
    A, B = edges[:, 0], edges[:, 1]
    XM = 0.5 * (Xall[A] + Xall[B])
    DM = _unit(Dall[A] + Dall[B])
    if curves is not None:
        _project_boundary_mids(XM, Xall, A, B, cnt, curves, L)
    # E: the corner two steps along from the side's first node in the first owning element
    e_own, k_own = np.divmod(first_side, 4)
    Ecorner = C[e_own, (k_own + 2) % 4]
    mid = N + side_edge  # (m,4) node index of each side's mid node
    cen = N + ne + np.arange(m)
    # 8-node serendipity at xi = eta = 0: corners -1/4, mid-edge nodes 1/2
    XC = -0.25 * Xall[C].sum(1) + 0.5 * XM[side_edge].sum(1)
    DC = _unit(-0.25 * Dall[C].sum(1) + 0.5 * DM[side_edge].sum(1))
    mp = np.full((ne + m, 3), -1, dtype=np.int64)
    mp[:ne] = np.column_stack([A, B, Ecorner])
    cp = np.full((ne + m, 8), -1, dtype=np.int64)
    cp[ne:] = np.column_stack([C, mid])
    # children k = [c_k, m_k, centre, m_(k-1)] (Fig. 15: child k starts at parent node k)
    ch = np.empty((m, 4, 4), dtype=np.int64)
    ch[:, :, 0] = C
    ch[:, :, 1] = mid
    ch[:, :, 2] = cen[:, None]
    ch[:, :, 3] = np.roll(mid, 1, axis=1)
    return _Split(nbr, XM, DM, XC, DC, mp, cp, ch.reshape(-1, 4))


def _project_boundary_mids(XM, Xall, A, B, cnt, curves, L: float) -> None:
    """Move the mid-edge nodes XM (in place) of the boundary edges (cnt == 1) whose two end nodes
    A, B lie on ``curves`` (within 1e-9 L) onto the curve."""
    bnd = np.flatnonzero(cnt == 1)
    if bnd.size:
        tol = 1e-9 * L
        on = (np.linalg.norm(curves(Xall[A[bnd]]) - Xall[A[bnd]], axis=1) <= tol) & (
            np.linalg.norm(curves(Xall[B[bnd]]) - Xall[B[bnd]], axis=1) <= tol
        )
        sel = bnd[on]
        if sel.size:
            XM[sel] = curves(XM[sel])


def _inherited_node_sets(node_sets, N: int, node_level, mid_parent, centre_parent, levels: int) -> dict:
    """{name: sorted background node indices} of the level-0 ``node_sets`` extended level by level:
    a mid-edge node is in when both edge ends are, a centre when all four corners are."""
    out = {}
    for name, idx in node_sets.items():
        inset = np.zeros(N, dtype=bool)
        inset[idx] = True
        for l in range(1, levels + 1):
            nodes = np.flatnonzero(node_level == l)
            mp = mid_parent[nodes]
            ism = mp[:, 0] >= 0
            inset[nodes[ism]] = inset[mp[ism, 0]] & inset[mp[ism, 1]]
            cp = centre_parent[nodes[~ism], :4]
            inset[nodes[~ism]] = inset[cp].all(1)
        out[name] = np.flatnonzero(inset)
    return out


_VARIANT_CHUNK = 1 << 14
"""Elements per choose_variant call when a level's variants are chosen (transition_variants):
~40 MB of temporaries at most."""


class BackgroundMesh:
    """All levels of the 1-to-4 subdivision of a level-0 quad mesh (Section 5.1).

    Attributes (background node index b in 0..Nb-1; level-0 nodes keep their indices):
    ``Xo``, ``Xn`` (Nb,3); ``levels``; ``n0``; ``conn[l]`` (n0*4**l, 4); ``nbr[l]`` (n0*4**l, 4)
    same-level element across edge k (-1 on the boundary; levels 0..levels-1);
    ``node_level`` (Nb,); ``mid_parent`` (Nb,3) [A, B, E]; ``centre_parent`` (Nb,8);
    ``node_sets`` {name: sorted background node indices}; ``level0`` the input ShellMesh.
    """

    def __init__(self):  # use from_level0
        pass

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_level0(
        cls, mesh: ShellMesh, levels: int = 3, curves=None, transitions: str | None = None
    ) -> "BackgroundMesh":
        """All levels of ``mesh`` split ``levels`` times; ``curves`` places new boundary nodes on
        the true curve; ``transitions`` is the variant policy of the transition patterns
        (transition.TRANSITION_POLICIES; None: transition.DEFAULT_TRANSITIONS)."""
        from .transition import DEFAULT_TRANSITIONS, check_policy

        transitions = check_policy(DEFAULT_TRANSITIONS if transitions is None else transitions)
        levels_i = _checked_levels(mesh, levels)
        self = cls()
        self.levels, self.n0, self.level0, self.transitions = levels_i, len(mesh.quads), mesh, transitions
        lev = [np.zeros(mesh.n_nodes, dtype=np.int64)]
        midp = [np.full((mesh.n_nodes, 3), -1, dtype=np.int64)]
        cenp = [np.full((mesh.n_nodes, 8), -1, dtype=np.int64)]
        conn = [mesh.quads.copy()]
        nbr = []
        N = mesh.n_nodes
        Xall, Dall = mesh.nodes.astype(float), mesh.directors.astype(float)
        L = mesh.characteristic_length()
        for l in range(levels_i):
            sp = _split_level(conn[l], Xall, Dall, N, curves, L)
            nbr.append(sp.nbr)
            lev += [np.full(len(sp.mid_parent), l + 1, dtype=np.int64)]
            midp.append(sp.mid_parent)
            cenp.append(sp.centre_parent)
            conn.append(sp.children)
            N += len(sp.mid_parent)
            Xall = np.concatenate([Xall, sp.XM, sp.XC])
            Dall = np.concatenate([Dall, sp.DM, sp.DC])
        self.Xo, self.Xn = Xall, Dall
        self.node_level = np.concatenate(lev)
        self.mid_parent = np.concatenate(midp)
        self.centre_parent = np.concatenate(cenp)
        self.conn, self.nbr = conn, nbr
        self.node_sets = _inherited_node_sets(
            mesh.node_sets, N, self.node_level, self.mid_parent, self.centre_parent, levels_i
        )
        return self

    # ------------------------------------------------------------------ sizes, labels
    n_nodes = property(lambda self: len(self.Xo))

    def n_elements(self, level: int) -> int:
        return self.n0 * 4 ** int(level)

    def label(self, level: int, index: int) -> str:
        """The paper's label of element (level, index): ``i0-c1-...-cl``, c = child number 1..4."""
        level, index = int(level), int(index)
        if not (0 <= level <= self.levels and 0 <= index < self.n_elements(level)):
            raise InputError(f"no element ({level}, {index}) in a background mesh of {self.levels} levels")
        digits = []
        for _ in range(level):
            index, k = divmod(index, 4)
            digits.append(str(k + 1))
        return "-".join([str(index)] + digits[::-1])

    def from_label(self, text: str) -> tuple[int, int]:
        """(level, index) of a label ``i0-c1-...`` (c in 1..4)."""
        parts = str(text).strip().split("-")
        try:
            i0 = int(parts[0])
            cs = [int(p) for p in parts[1:]]
        except ValueError:
            raise InputError(f"bad element label {text!r}: expected i0-c1-c2-... with c in 1..4") from None
        if not (0 <= i0 < self.n0) or any(c not in (1, 2, 3, 4) for c in cs) or len(cs) > self.levels:
            raise InputError(f"bad element label {text!r} for {self.n0} level-0 elements and {self.levels} levels")
        e = i0
        for c in cs:
            e = 4 * e + c - 1
        return len(cs), e

    def transition_variants(self, level: int, index: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """(K,) variant of the transition pattern for refined-edge ``mask`` (K,) that each element
        (level, index) (K,) takes (transition.choose_variant on its X_o under this mesh's
        ``transitions`` policy).  Memoised per level and
        mask, since the geometry never changes: the first time a mask is asked for on a level, the
        variant of every element of that level is chosen in one vectorised call (choose_variant
        treats each element apart from the others, so this is the per-element choice; 195 small
        calls took 0.8 s of the paper path's remeshing, docs/adaptivity.md)."""
        from .transition import TABLE, choose_variant

        l = int(level)
        cache = self.__dict__.setdefault("_variants", {})
        if l not in cache:
            cache[l] = np.full((self.n_elements(l), 16), -1, dtype=np.int8)
        tab = cache[l]
        index, mask = np.asarray(index, dtype=np.int64), np.asarray(mask, dtype=np.int64)
        for m in np.unique(mask):
            if tab[0, m] >= 0:
                continue
            if len(TABLE[int(m)][1]) == 1:
                tab[:, m] = 0
                continue
            n = self.n_elements(l)
            for a in range(0, n, _VARIANT_CHUNK):  # bounded temporaries on a deep background
                e = np.arange(a, min(a + _VARIANT_CHUNK, n))
                ch = self.conn[l + 1][(4 * e[:, None] + np.arange(4)).ravel()].reshape(-1, 4, 4)
                loc = np.concatenate([self.conn[l][e], ch[:, :, 1], ch[:, :1, 2]], axis=1)
                tab[e, m] = choose_variant(int(m), self.Xo[loc], self.transitions)
        return tab[index, mask]

    def element_nodes(self, level: int, index) -> np.ndarray:
        """Background node indices (…,4) of element(s) (level, index)."""
        return self.conn[int(level)][index]

    def mesh_at_level(self, level: int) -> ShellMesh:
        """The uniform mesh of one level as a ShellMesh (nodes renumbered, sets inherited)."""
        C = self.conn[int(level)]
        nodes = np.unique(C)
        remap = np.full(self.n_nodes, -1, dtype=np.int64)
        remap[nodes] = np.arange(len(nodes))
        sets = {k: remap[np.intersect1d(v, nodes)] for k, v in self.node_sets.items()}
        return ShellMesh(self.Xo[nodes], quads=remap[C], directors=self.Xn[nodes], node_sets=sets, check=False)


def boundary_area_report(mesh: ShellMesh, levels: int, curves, exact: float | None = None) -> dict:
    """Mid-surface area [length^2] of the finest background level with new boundary nodes averaged
    (straight chords) and projected onto the true curve (``curves``), and their difference
    (Section 5.1: averaging cuts the corners of a curved boundary).  ``exact``: the true area,
    reported with the relative errors when given."""
    a_avg = BackgroundMesh.from_level0(mesh, levels).mesh_at_level(levels).area()
    a_prj = BackgroundMesh.from_level0(mesh, levels, curves).mesh_at_level(levels).area()
    out = {
        "level0": mesh.area(),
        "averaged": a_avg,
        "projected": a_prj,
        "difference": a_prj - a_avg,
        "relative_difference": (a_prj - a_avg) / a_prj,
    }
    if exact is not None:
        out.update(exact=float(exact), error_averaged=(a_avg - exact) / exact, error_projected=(a_prj - exact) / exact)
    return out
