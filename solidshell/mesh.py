"""ShellMesh: mid-surface nodes X_o, unit directors X_n, quads and triangles, named node sets.

Coordinates are 3-D in the scene's length unit (cm for the paper's scenes).  Elements are numbered
counter-clockwise about their director (seen from +Z for a flat mesh with directors +Z), the order
of Eq. (1) and Eq. (10).  A mesh may mix quadrilaterals and triangles (adaptivity needs both).
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

_EMPTY_Q = np.zeros((0, 4), dtype=np.int64)
_EMPTY_T = np.zeros((0, 3), dtype=np.int64)


def _as_cells(cells, k: int, name: str) -> np.ndarray:
    if cells is None:
        return np.zeros((0, k), dtype=np.int64)
    a = np.asarray(cells)
    if a.size == 0:
        return np.zeros((0, k), dtype=np.int64)
    if a.ndim != 2 or a.shape[1] != k:
        raise InputError(f"{name} must be an integer array of shape (M,{k}), got shape {a.shape}")
    if not np.issubdtype(a.dtype, np.integer):
        if not np.all(np.equal(np.mod(a, 1), 0)):
            raise InputError(f"{name} must hold integer node indices")
    return np.ascontiguousarray(a, dtype=np.int64)


def _corner_normals(X: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """(M,k,3) non-normalised normals at each corner: (next - this) x (prev - this)."""
    P = X[cells]
    nxt = np.roll(P, -1, axis=1) - P
    prv = np.roll(P, 1, axis=1) - P
    return np.cross(nxt, prv)


class ShellMesh:
    """A shell mid-surface mesh with nodal directors.

    Parameters
    ----------
    nodes : (N,3) array_like [length]
        Mid-surface node positions X_o (a (N,2) array is taken as z = 0).
    quads : (M,4) int array, optional;  tris : (K,3) int array, optional
        Element connectivity, counter-clockwise about the director.
    directors : (N,3) array_like, optional
        Initial directors X_n; normalised to unit length.  Default: the area-weighted average of the
        unit normals of the elements meeting at each node (Section 2: X_n is the unit normal).
    node_sets : dict[str, array of node indices], optional
        Named node sets (``clamped``, ``corners``, ...).
    check : bool
        Validate the mesh (indices in range, no duplicate nodes, no degenerate or inverted element).
    """

    def __init__(self, nodes, quads=None, tris=None, directors=None, node_sets=None, check=True):
        X = np.asarray(nodes, dtype=float)
        if X.ndim != 2 or X.shape[1] not in (2, 3):
            raise InputError(f"nodes must have shape (N,3), got {X.shape}")
        if X.shape[1] == 2:
            X = np.column_stack([X, np.zeros(len(X))])
        self.nodes = np.ascontiguousarray(X)
        self.quads = _as_cells(quads, 4, "quads")
        self.tris = _as_cells(tris, 3, "tris")
        if self.n_elements == 0:
            raise InputError("a mesh needs at least one element")
        for name, c in (("quads", self.quads), ("tris", self.tris)):
            if c.size and (c.min() < 0 or c.max() >= len(X)):
                raise InputError(f"{name} refer to nodes outside 0..{len(X) - 1}")
        if directors is None:
            self.directors = self.averaged_normals()
        else:
            D = np.asarray(directors, dtype=float)
            if D.shape != X.shape:
                raise InputError(f"directors must have shape {X.shape}, got {D.shape}")
            n = np.linalg.norm(D, axis=1)
            if not np.all(np.isfinite(n)) or np.any(n <= 0.0):
                raise InputError("every director must be a finite non-zero vector")
            # leave already-unit directors bit-for-bit (a file round trip must not change them)
            unit = np.abs(n - 1.0) <= 4 * np.finfo(float).eps
            self.directors = np.where(unit[:, None], D, D / n[:, None])
        self.node_sets = {}
        for k, v in (node_sets or {}).items():
            self.add_node_set(k, v)
        # per-element labels written with the run's fields (quads, then triangles), e.g. an
        # adaptive mesh's refinement level (adapt/forest.py, solidshell/fields.py)
        self.cell_tags: dict[str, np.ndarray] = {}
        if check:
            self.validate()

    # ------------------------------------------------------------------ sizes
    n_nodes = property(lambda self: len(self.nodes))
    n_quads = property(lambda self: len(self.quads))
    n_tris = property(lambda self: len(self.tris))
    n_elements = property(lambda self: len(self.quads) + len(self.tris))

    def __repr__(self) -> str:
        return (
            f"ShellMesh({self.n_nodes} nodes, {self.n_quads} quads, {self.n_tris} tris, sets={sorted(self.node_sets)})"
        )

    # -------------------------------------------------------------- node sets
    def add_node_set(self, name: str, nodes) -> None:
        idx = np.unique(np.asarray(nodes, dtype=np.int64).ravel())
        if idx.size and (idx.min() < 0 or idx.max() >= self.n_nodes):
            raise InputError(f"node set {name!r} refers to nodes outside 0..{self.n_nodes - 1}")
        self.node_sets[str(name)] = idx

    def node_set(self, name: str) -> np.ndarray:
        """Indices of the named node set; an unknown or empty set is an error."""
        try:
            idx = self.node_sets[name]
        except KeyError:
            raise InputError(
                f"mesh has no node set {name!r}; it has: {', '.join(sorted(self.node_sets)) or 'none'}"
            ) from None
        if idx.size == 0:
            raise InputError(f"node set {name!r} selects no node")
        return idx

    # --------------------------------------------------------------- geometry
    def averaged_normals(self) -> np.ndarray:
        """Unit nodal normals: sum over incident elements of their corner normals (area-weighted)."""
        acc = np.zeros_like(self.nodes)
        for cells in (self.quads, self.tris):
            if len(cells):
                cn = _corner_normals(self.nodes, cells)
                np.add.at(acc, cells.ravel(), cn.reshape(-1, 3))
        n = np.linalg.norm(acc, axis=1)
        if np.any(n <= 0.0):
            bad = np.flatnonzero(n <= 0.0)
            raise InputError(
                f"{bad.size} node(s) belong to no element or only to degenerate ones "
                f"(first: node {bad[0]}); cannot define their directors"
            )
        return acc / n[:, None]

    def element_areas(self) -> tuple[np.ndarray, np.ndarray]:
        """(quad areas, triangle areas) [length^2] of the mid-surface (bilinear quads: exact by
        splitting along both diagonals and averaging, exact for planar quads)."""
        X = self.nodes
        qa = np.zeros(0)
        if len(self.quads):
            P = X[self.quads]
            qa = 0.5 * np.linalg.norm(np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]), axis=1)
        ta = np.zeros(0)
        if len(self.tris):
            P = X[self.tris]
            ta = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        return qa, ta

    def area(self) -> float:
        qa, ta = self.element_areas()
        return float(qa.sum() + ta.sum())

    def characteristic_length(self) -> float:
        """Bounding-box diagonal [length], the scale for geometric tolerances."""
        return float(np.linalg.norm(self.nodes.max(0) - self.nodes.min(0)))

    def edges(self) -> np.ndarray:
        """(E,2) unique undirected edges, sorted node pairs."""
        parts = []
        for cells in (self.quads, self.tris):
            if len(cells):
                cells.shape[1]
                parts.append(np.stack([cells, np.roll(cells, -1, axis=1)], axis=2).reshape(-1, 2))
        e = np.sort(np.concatenate(parts), axis=1)
        return np.unique(e, axis=0)

    def boundary_edges(self) -> np.ndarray:
        """(B,2) directed edges that belong to exactly one element (counter-clockwise order)."""
        parts = []
        for cells in (self.quads, self.tris):
            if len(cells):
                parts.append(np.stack([cells, np.roll(cells, -1, axis=1)], axis=2).reshape(-1, 2))
        e = np.concatenate(parts)
        key = np.sort(e, axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        return e[cnt[inv.ravel()] == 1]

    # ------------------------------------------------------------- validation
    def validate(self, rel_tol: float = 1e-12) -> None:
        """Raise InputError for duplicate nodes and degenerate or inverted elements.

        An element is inverted when the normal at any of its corners points against the director at
        that corner; degenerate when a corner normal is below ``rel_tol`` * L^2 (L = mesh size).
        """
        X = self.nodes
        if not np.all(np.isfinite(X)):
            raise InputError("node coordinates must be finite")
        L = self.characteristic_length()
        if L <= 0.0:
            raise InputError("all nodes coincide")
        # duplicate nodes: coincident within 1e-9 L
        q = np.round(X / (L * 1e-9)).astype(np.int64)
        _, first, cnt = np.unique(q, axis=0, return_index=True, return_counts=True)
        if np.any(cnt > 1):
            raise InputError(f"{int(np.sum(cnt - 1))} duplicate node(s) (coincident within 1e-9 of the mesh size)")
        for name, cells in (("quad", self.quads), ("triangle", self.tris)):
            if not len(cells):
                continue
            if np.any(
                [len(set(r)) < cells.shape[1] for r in cells[np.any(np.diff(np.sort(cells, 1), axis=1) == 0, axis=1)]]
            ):
                raise InputError(f"a {name} repeats a node")
            cn = _corner_normals(X, cells)
            mag = np.linalg.norm(cn, axis=2)
            if np.any(mag <= rel_tol * L * L):
                e = int(np.argwhere(mag <= rel_tol * L * L)[0, 0])
                raise InputError(f"{name} {e} is degenerate (zero area at a corner)")
            dots = np.einsum("ekc,ekc->ek", cn, self.directors[cells])
            if np.any(dots <= 0.0):
                e = int(np.argwhere(dots <= 0.0)[0, 0])
                raise InputError(f"{name} {e} is inverted (not counter-clockwise about its director) or non-convex")

    # ------------------------------------------------------------------ copies
    def copy(self) -> "ShellMesh":
        m = ShellMesh.__new__(ShellMesh)
        m.nodes = self.nodes.copy()
        m.quads = self.quads.copy()
        m.tris = self.tris.copy()
        m.directors = self.directors.copy()
        m.node_sets = {k: v.copy() for k, v in self.node_sets.items()}
        return m

    # ----------------------------------------------------------------- meshio
    def to_meshio(self, point_data=None, cell_data=None):
        """A meshio.Mesh with 'quad' and/or 'triangle' blocks; directors as point data 'director'
        and each node set as a 0/1 point-data field 'set:<name>'."""
        import meshio

        cells = []
        if len(self.quads):
            cells.append(("quad", self.quads))
        if len(self.tris):
            cells.append(("triangle", self.tris))
        pd = {"director": self.directors}
        for k, v in self.node_sets.items():
            f = np.zeros(self.n_nodes, dtype=np.int32)
            f[v] = 1
            pd[f"set:{k}"] = f
        pd.update(point_data or {})
        return meshio.Mesh(self.nodes, cells, point_data=pd, cell_data=cell_data or {})

    @classmethod
    def from_meshio(cls, m, check=True) -> "ShellMesh":
        """Build from a meshio.Mesh (its 'quad' and 'triangle' blocks; other cells are ignored).
        Point data 'director' and 'set:<name>' written by :meth:`to_meshio` are restored."""
        quads = [c.data for c in m.cells if c.type == "quad"]
        tris = [c.data for c in m.cells if c.type == "triangle"]
        if not quads and not tris:
            raise InputError("the mesh file holds no quad or triangle cells")
        pts = np.asarray(m.points, dtype=float)
        used = np.unique(np.concatenate([np.asarray(c).ravel() for c in quads + tris]))
        # drop nodes that belong to no surface element (e.g. gmsh geometry points)
        remap = -np.ones(len(pts), dtype=np.int64)
        remap[used] = np.arange(len(used))
        pd = m.point_data or {}
        D = pd.get("director")
        sets = {k[4:]: np.flatnonzero(np.asarray(v)[used] > 0) for k, v in pd.items() if k.startswith("set:")}
        return cls(
            pts[used],
            quads=remap[np.concatenate(quads)] if quads else None,
            tris=remap[np.concatenate(tris)] if tris else None,
            directors=None if D is None else np.asarray(D, float)[used],
            node_sets=sets,
            check=check,
        )

    # --------------------------------------------------------------- skfem
    def to_skfem(self):
        """scikit-fem mesh of a flat mesh (z dropped; raises unless all z are equal).

        Returns MeshQuad1 for an all-quad mesh and MeshTri1 for an all-triangle mesh (skfem's 2-D
        meshes do not mix types).  Node numbering is preserved, so nodal arrays carry over.
        """
        import skfem

        z = self.nodes[:, 2]
        if np.ptp(z) > 1e-12 * max(self.characteristic_length(), 1.0):
            raise InputError("to_skfem needs a flat mesh in a z = const plane")
        p = self.nodes[:, :2].T.copy()
        if len(self.quads) and not len(self.tris):
            return skfem.MeshQuad1(p, self.quads.T.copy())
        if len(self.tris) and not len(self.quads):
            return skfem.MeshTri1(p, self.tris.T.copy())
        raise InputError("scikit-fem cannot hold a mixed quad/triangle mesh")
