"""Adaptive mesh state: the active leaves of the background mesh, split/merge with 2:1 balance,
and the computational mesh of quads and transition triangles (paper Sections 5.1-5.3, 5.5).

State: one bool array per level, ``leaf[l][e]`` = element (l, e) is active (a leaf).  An element
*exists* when it is a leaf or has a leaf below it; it is *split* when it exists and is no leaf.

2:1 balance (Section 5.3: adjacent elements never differ by more than one level) is kept in this
equivalent form: every split element's same-level edge neighbours exist.  A split of (l, e) whose
neighbour at level l does not exist first splits that neighbour's parent (a leaf at level l-1),
recursively; a merge of (l, e) is vetoed while a same-level neighbour of one of its children is split.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..mesh import ShellMesh
from .background import BackgroundMesh
from .transition import TABLE

_STATE_VERSION = 1


@dataclass
class ActiveMesh:
    """The computational mesh of an adaptive state.

    mesh : ShellMesh of the active nodes (quads, then transition triangles), directors bg.Xn
    nodes : (n_nodes,) background index of each mesh node (sorted ascending)
    elem_leaf : (n_elements, 2) (level, index) of the leaf each element belongs to, quads first
        then triangles (the Model's element order)
    elem_kind : (n_elements,) 0 = plain leaf quad, else the transition pattern id (transition.py)
    active : (Nb,) bool, the paper's active-node array over the background nodes (Section 5.1)
    """

    mesh: ShellMesh
    nodes: np.ndarray
    elem_leaf: np.ndarray
    elem_kind: np.ndarray
    active: np.ndarray

    def __post_init__(self):
        # the labels written with the run's fields (solidshell/fields.py)
        self.mesh.cell_tags.update(refinement_level=self.elem_level, transition_pattern=self.elem_kind)

    @property
    def elem_level(self) -> np.ndarray:
        """Level of each element; transition elements between levels i and i+1 are i + 1/2."""
        return self.elem_leaf[:, 0] + 0.5 * (self.elem_kind > 0)


def _as_items(items, levels):
    """Normalise (level, index) pairs: an (K,2) int array."""
    a = np.asarray(items, dtype=np.int64)
    if a.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    a = a.reshape(-1, 2)
    if a[:, 0].min() < 0 or a[:, 0].max() > levels:
        raise InputError(f"element levels must lie in 0..{levels}")
    return a


def _check_index(a, bg):
    """(K,2) items whose index lies outside 0..n0*4**level-1 -> InputError naming the first."""
    bad = (a[:, 1] < 0) | (a[:, 1] >= bg.n0 * 4 ** a[:, 0])
    if bad.any():
        l, e = a[np.argmax(bad)]
        raise InputError(f"no element ({l}, {e}): level {l} has {bg.n_elements(l)} elements")
    return a


class AdaptiveMesh:
    """Active leaves of a :class:`BackgroundMesh`, starting with every level-0 element active."""

    def __init__(self, bg: BackgroundMesh):
        self.bg = bg
        self.leaf = [np.zeros(bg.n_elements(l), dtype=bool) for l in range(bg.levels + 1)]
        self.leaf[0][:] = True
        self._exists = None

    # ------------------------------------------------------------------ derived state
    @property
    def exists(self) -> list[np.ndarray]:
        """Per level: element is a leaf or has leaves below it (bottom-up, cached until a change)."""
        if self._exists is None:
            L = self.bg.levels
            ex = [None] * (L + 1)
            ex[L] = self.leaf[L].copy()
            for l in range(L - 1, -1, -1):
                ex[l] = self.leaf[l] | ex[l + 1].reshape(-1, 4).any(1)
            self._exists = ex
        return self._exists

    def split_flags(self, l: int) -> np.ndarray:
        return self.exists[l] & ~self.leaf[l]

    def leaves(self) -> np.ndarray:
        """(K,2) (level, index) of every active leaf, by level then index."""
        return np.concatenate(
            [np.column_stack([np.full(f.sum(), l), np.flatnonzero(f)]) for l, f in enumerate(self.leaf)]
        ).astype(np.int64)

    def n_leaves(self) -> int:
        return int(sum(f.sum() for f in self.leaf))

    def _changed(self):
        self._exists = None

    # ------------------------------------------------------------------ split / merge
    def split(self, items) -> int:
        """Split the given leaves (K,2) (level, index) 1-to-4, plus whatever coarser leaves 2:1
        balance requires.  Non-leaves and finest-level elements are ignored.  Returns the number
        of elements split."""
        bg = self.bg
        L = bg.levels
        a = _check_index(_as_items(items, L), bg)
        want = [np.zeros(bg.n_elements(l), dtype=bool) for l in range(L)]
        for l in range(L):
            e = a[a[:, 0] == l, 1]
            want[l][e[self.leaf[l][e]]] = True
        ex = self.exists
        # balance propagates only downwards in level, so one pass from the finest level suffices
        for l in range(L - 1, 0, -1):
            nb = bg.nbr[l][want[l]].ravel()
            nb = nb[nb >= 0]
            missing = nb[~ex[l][nb]]
            if missing.size:
                want[l - 1][missing // 4] = True
        n = 0
        for l in range(L):
            e = np.flatnonzero(want[l])
            self.leaf[l][e] = False
            ch = (4 * e[:, None] + np.arange(4)).ravel()
            self.leaf[l + 1][ch] = True
            n += e.size
        self._changed()
        return n

    def mergeable(self, l: int) -> np.ndarray:
        """Indices of level-l elements whose four children are leaves and whose merge keeps 2:1
        balance (no same-level neighbour of a child is split)."""
        if l >= self.bg.levels:
            return np.zeros(0, dtype=np.int64)
        cand = np.flatnonzero(self.leaf[l + 1].reshape(-1, 4).all(1))
        if l + 1 < self.bg.levels and cand.size:
            ch = (4 * cand[:, None] + np.arange(4)).ravel()
            nb = self.bg.nbr[l + 1][ch]
            sp = self.split_flags(l + 1)
            bad = ((nb >= 0) & sp[np.maximum(nb, 0)]).reshape(-1, 16).any(1)
            cand = cand[~bad]
        return cand

    def merge(self, parents) -> int:
        """Merge the four children of each given parent (K,2) (level, index) back into it (the
        reverse of split).  Parents whose children are not all leaves, or whose merge would break
        2:1 balance, are left alone (vetoed).  Processed finest level first, so a parent and its
        grandparent can merge in one call.  Returns the number of merges done."""
        L = self.bg.levels
        a = _check_index(_as_items(parents, L), self.bg)
        n = 0
        for l in range(L - 1, -1, -1):
            e = np.unique(a[a[:, 0] == l, 1])
            if not e.size:
                continue
            ok = np.intersect1d(e, self.mergeable(l), assume_unique=True)
            self.leaf[l + 1][(4 * ok[:, None] + np.arange(4)).ravel()] = False
            self.leaf[l][ok] = True
            self._changed()
            n += ok.size
        return n

    def refine_all(self) -> None:
        """Split every leaf until all leaves are at the finest level."""
        for l in range(self.bg.levels):
            self.split(np.column_stack([np.full(self.leaf[l].sum(), l), np.flatnonzero(self.leaf[l])]))

    def coarsen_all(self) -> None:
        """Merge everything back to the level-0 mesh."""
        for l in range(self.bg.levels - 1, -1, -1):
            m = self.mergeable(l)
            self.merge(np.column_stack([np.full(m.size, l), m]))

    # ------------------------------------------------------------------ checks
    def balance_violations(self) -> int:
        """Number of split elements with a same-level neighbour that does not exist (0 when the
        state is 2:1 balanced)."""
        n = 0
        for l in range(1, self.bg.levels):
            nb = self.bg.nbr[l][self.split_flags(l)].ravel()
            nb = nb[nb >= 0]
            n += int((~self.exists[l][nb]).sum())
        return n

    # ------------------------------------------------------------------ computational mesh
    def refined_mask(self, l: int, e: np.ndarray) -> np.ndarray:
        """Bit k set when the same-level neighbour of leaf (l, e) across edge k is split."""
        if l >= self.bg.levels:
            return np.zeros(len(e), dtype=np.int64)
        nb = self.bg.nbr[l][e]
        sp = self.split_flags(l)
        ref = (nb >= 0) & sp[np.maximum(nb, 0)]
        return (ref * (1 << np.arange(4))).sum(1)

    def active_mesh(self, check: bool = False) -> ActiveMesh:
        """The computational mesh: plain leaves as quads, leaves beside finer neighbours as hybrid
        macro-transition patches (transition.py)."""
        bg = self.bg
        L = bg.levels
        lv, ee, mk, lc, vr = [], [], [], [], []
        for l in range(L + 1):
            e = np.flatnonzero(self.leaf[l])
            if not e.size:
                continue
            loc = np.full((e.size, 9), -1, dtype=np.int64)
            loc[:, :4] = bg.conn[l][e]
            if l < L:
                ch = bg.conn[l + 1][(4 * e[:, None] + np.arange(4)).ravel()].reshape(-1, 4, 4)
                loc[:, 4:8] = ch[:, :, 1]
                loc[:, 8] = ch[:, 0, 2]
            lv.append(np.full(e.size, l))
            ee.append(e)
            mask = self.refined_mask(l, e)
            mk.append(mask)
            lc.append(loc)
            vr.append(bg.transition_variants(l, e, mask) if mask.any() else np.zeros(e.size, np.int8))
        lv, ee, mk, lc, vr = (np.concatenate(x) for x in (lv, ee, mk, lc, vr))
        qparts, tparts = [], []  # (cells, level, index, sub, kind)
        for m in np.unique(mk):
            sel = np.flatnonzero(mk == m)
            pid, variants = TABLE[int(m)]
            pick = vr[sel]
            for v, (q, t) in enumerate(variants):
                sv = sel[pick == v]
                for cells, parts in ((q, qparts), (t, tparts)):
                    if len(cells) and sv.size:
                        c = lc[sv][:, cells]  # (n, k, nn)
                        n, k = c.shape[:2]
                        parts.append(
                            (
                                c.reshape(n * k, -1),
                                np.repeat(lv[sv], k),
                                np.repeat(ee[sv], k),
                                np.tile(np.arange(k), n),
                                np.full(n * k, pid),
                            )
                        )

        def gather(parts, nn):
            if not parts:
                return np.zeros((0, nn), np.int64), np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
            c, lv, ix, sub, kind = (np.concatenate(x) for x in zip(*parts))
            # leaf order (level, index, sub-element), not mask-group order: the all-level-0 state
            # then reproduces the user's element numbering, and equal states give equal meshes
            order = np.lexsort((sub, ix, lv))
            return c[order], np.column_stack([lv, ix])[order], kind[order]

        Q, qleaf, qkind = gather(qparts, 4)
        T, tleaf, tkind = gather(tparts, 3)
        nodes = np.unique(np.concatenate([Q.ravel(), T.ravel()]))
        remap = np.full(bg.n_nodes, -1, dtype=np.int64)
        remap[nodes] = np.arange(nodes.size)
        sets = {}
        for k, v in bg.node_sets.items():
            r = remap[v]
            sets[k] = r[r >= 0]
        mesh = ShellMesh(
            bg.Xo[nodes], quads=remap[Q], tris=remap[T], directors=bg.Xn[nodes], node_sets=sets, check=check
        )
        return ActiveMesh(mesh, nodes, np.concatenate([qleaf, tleaf]), np.concatenate([qkind, tkind]), remap >= 0)

    # ------------------------------------------------------------------ checkpoint
    def state_arrays(self) -> dict[str, np.ndarray]:
        """Arrays that restore this state exactly with :meth:`from_state_arrays`."""
        out = {f"leaf_{l}": f.copy() for l, f in enumerate(self.leaf)}
        out["meta"] = np.array([_STATE_VERSION, self.bg.levels, self.bg.n0, self.bg.n_nodes], dtype=np.int64)
        return out

    @classmethod
    def from_state_arrays(cls, bg: BackgroundMesh, arrays) -> "AdaptiveMesh":
        meta = np.asarray(arrays["meta"])
        if list(meta[1:]) != [bg.levels, bg.n0, bg.n_nodes] or meta[0] != _STATE_VERSION:
            raise InputError(
                f"adaptive state (levels, n0, nodes) = {tuple(meta[1:])} does not match the "
                f"background mesh {(bg.levels, bg.n0, bg.n_nodes)}"
            )
        self = cls(bg)
        for l in range(bg.levels + 1):
            f = np.asarray(arrays[f"leaf_{l}"], dtype=bool)
            if f.shape != self.leaf[l].shape:
                raise InputError(f"adaptive state leaf_{l} has shape {f.shape}, expected {self.leaf[l].shape}")
            self.leaf[l] = f.copy()
        return self
