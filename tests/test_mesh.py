"""Tests of solidshell.mesh.ShellMesh: construction, validation errors, node sets, meshio round
trips and scikit-fem conversion.  Small hand-made meshes only; runs in about a second."""

import numpy as np
import pytest

from solidshell.errors import InputError
from solidshell.mesh import ShellMesh

# 3x2 grid of unit squares, counter-clockwise seen from +Z:
#  6--7--8--9
#  |  |  |  |
#  2--3--4--5      (nodes 0,1 start the bottom row: 0--1--10--11)
SQ = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=float)


def grid(nx=3, ny=2, z=None):
    """(nx x ny) unit-square quads, row-major nodes, counter-clockwise from +Z."""
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    X = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size) if z is None else z(x.ravel(), y.ravel())])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    n0 = (j * (nx + 1) + i).ravel()
    quads = np.column_stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1])
    return X, quads


def split(quads):
    """Each quad into two counter-clockwise triangles."""
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def mixed_curved_mesh():
    """A non-flat mesh with quads and triangles, non-trivial directors and two node sets."""
    X, q = grid(3, 2, z=lambda x, y: 0.1 * x * x - 0.05 * y)
    return ShellMesh(
        X, quads=q[:4], tris=split(q[4:]), node_sets={"left": np.flatnonzero(X[:, 0] == 0.0), "corner": [11]}
    )


# --------------------------------------------------------------------------- construction
def test_flat_grid_defaults():
    X, q = grid()
    m = ShellMesh(X[:, :2], quads=q)  # (N,2) nodes are taken as z = 0
    assert (m.n_nodes, m.n_quads, m.n_tris, m.n_elements) == (12, 6, 0, 6)
    assert np.array_equal(m.nodes[:, 2], np.zeros(12))
    assert np.array_equal(m.directors, np.tile([0.0, 0.0, 1.0], (12, 1)))
    assert m.area() == 6.0  # unit squares: exact in floating point
    assert len(m.edges()) == 17 and len(m.boundary_edges()) == 10


def test_default_directors_are_unit_averaged_normals():
    m = mixed_curved_mesh()
    assert np.allclose(np.linalg.norm(m.directors, axis=1), 1.0, rtol=0, atol=1e-15)  # rounding
    # on the plane part z = -0.05 y at x = 0 the normal is (0, 0.05, 1)/|.|; the node there also
    # touches the curved part, so only its y and z components are the plane's
    n0 = m.directors[0]
    assert n0[1] > 0.0 and n0[2] > 0.99


def test_given_directors_are_normalised_and_unit_ones_kept_exactly():
    X, q = grid(1, 1)
    D = np.tile([0.0, 0.0, 2.0], (4, 1))
    assert np.array_equal(ShellMesh(X, q, directors=D).directors, np.tile([0.0, 0.0, 1.0], (4, 1)))
    U = np.tile([0.6, 0.0, 0.8], (4, 1))  # unit to rounding: must not be touched
    assert np.array_equal(ShellMesh(X, q, directors=U).directors, U)


def test_area_of_a_planar_quad_is_exact():
    X = np.array([[0, 0, 0], [3, 0, 0], [2, 2, 0], [0, 1, 0]], dtype=float)
    # shoelace area of this quad is 4.0; the diagonal cross product is exact for planar quads
    assert ShellMesh(X, quads=[[0, 1, 2, 3]]).area() == pytest.approx(4.0, rel=1e-15)  # rounding only


def test_copy_is_independent():
    m = mixed_curved_mesh()
    c = m.copy()
    c.nodes[0, 0] = 9.0
    c.node_sets["left"][0] = 5
    assert m.nodes[0, 0] == 0.0 and m.node_sets["left"][0] == 0


# --------------------------------------------------------------------------- bad input
def test_inverted_element():
    X, q = grid()
    q[2] = q[2, ::-1]  # one clockwise quad among ccw ones
    with pytest.raises(InputError, match="quad 2 is inverted"):
        ShellMesh(X, quads=q, directors=np.tile([0.0, 0.0, 1.0], (12, 1)))


def test_non_convex_quad():
    X = np.array([[0, 0], [2, 0], [0.5, 0.5], [0, 2]], dtype=float)  # re-entrant corner at node 2
    with pytest.raises(InputError, match="inverted .*or non-convex"):
        ShellMesh(X, quads=[[0, 1, 2, 3]], directors=np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_degenerate_elements():
    X = np.array([[0, 0], [1, 0], [2, 0], [0, 1]], dtype=float)
    with pytest.raises(InputError, match="triangle 0 is degenerate"):  # collinear corners
        ShellMesh(X, tris=[[0, 1, 2]], directors=np.tile([0.0, 0.0, 1.0], (4, 1)))
    with pytest.raises(InputError, match="quad 0 is degenerate"):  # 180-degree corner
        ShellMesh(X, quads=[[0, 1, 2, 3]], directors=np.tile([0.0, 0.0, 1.0], (4, 1)))
    with pytest.raises(InputError, match="repeats a node"):
        ShellMesh(X, quads=[[0, 1, 1, 3]], directors=np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_degenerate_elements_without_directors():
    X = np.array([[0, 0], [1, 0], [2, 0]], dtype=float)
    with pytest.raises(InputError, match="degenerate"):  # no normal: directors undefined
        ShellMesh(X, tris=[[0, 1, 2]])


def test_duplicate_nodes():
    X, q = grid(1, 1)
    X = np.vstack([X, X[3] + 1e-12])  # 1e-12 << 1e-9 x mesh size: a duplicate
    with pytest.raises(InputError, match="1 duplicate node"):
        ShellMesh(X, quads=[[0, 1, 3, 2], [0, 1, 4, 2]], directors=np.tile([0.0, 0.0, 1.0], (5, 1)))


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(nodes=np.zeros((3, 4)), tris=[[0, 1, 2]]), "shape"),
        (dict(nodes=SQ), "at least one element"),
        (dict(nodes=SQ, quads=[[0, 1, 3, 4]]), "outside"),
        (dict(nodes=SQ, quads=[[0, 1, 3]]), r"\(M,4\)"),
        (dict(nodes=SQ, quads=[[0, 1, 3, 2.5]]), "integer"),
        (dict(nodes=SQ, quads=[[0, 1, 3, 2]], directors=np.zeros((4, 3))), "non-zero"),
        (dict(nodes=SQ, quads=[[0, 1, 3, 2]], directors=np.ones((3, 3))), "shape"),
        (dict(nodes=SQ, quads=[[0, 1, 3, 2]], node_sets={"x": [7]}), "outside"),
        (
            dict(
                nodes=np.array([[0, 0], [1, 0], [np.nan, 1], [0, 1]]),
                quads=[[0, 1, 2, 3]],
                directors=np.tile([0.0, 0.0, 1.0], (4, 1)),
            ),
            "finite",
        ),
    ],
)
def test_bad_construction(kwargs, match):
    with pytest.raises(InputError, match=match):
        ShellMesh(**kwargs)


def test_node_sets():
    m = ShellMesh(SQ, quads=[[0, 1, 3, 2]], node_sets={"edge": [2, 0, 0], "none": []})
    assert np.array_equal(m.node_set("edge"), [0, 2])  # sorted and unique
    with pytest.raises(InputError, match="'none' selects no node"):
        m.node_set("none")
    with pytest.raises(InputError, match="no node set 'clamped'; it has: edge, none"):
        m.node_set("clamped")


# --------------------------------------------------------------------------- meshio
@pytest.mark.parametrize("ext", ["vtu", "xdmf"])
def test_meshio_round_trip_is_exact(tmp_path, ext):
    import meshio

    if ext == "xdmf":
        pytest.importorskip("h5py", reason="meshio's XDMF writer needs h5py")
    m = mixed_curved_mesh()
    path = tmp_path / f"mesh.{ext}"
    m.to_meshio(point_data={"u": np.arange(12.0)}).write(path)
    raw = meshio.read(path)
    # the file itself holds the exact arrays (binary/HDF5 storage: no decimal rounding)
    assert np.array_equal(raw.points, m.nodes)
    assert np.array_equal(raw.point_data["director"], m.directors)
    assert np.array_equal(raw.point_data["u"], np.arange(12.0))
    r = ShellMesh.from_meshio(raw)
    assert np.array_equal(r.nodes, m.nodes)
    assert np.array_equal(r.quads, m.quads) and np.array_equal(r.tris, m.tris)
    assert np.array_equal(r.directors, m.directors)
    assert r.node_sets.keys() == m.node_sets.keys()
    assert all(np.array_equal(r.node_sets[k], m.node_sets[k]) for k in m.node_sets)


def test_from_meshio_drops_loose_points_and_needs_surface_cells():
    import meshio

    X, q = grid(1, 1)
    pts = np.vstack([[5.0, 5.0, 0.0], X])  # a geometry point before the mesh
    m = ShellMesh.from_meshio(meshio.Mesh(pts, [("vertex", [[0]]), ("quad", q + 1)]))
    assert np.array_equal(m.nodes, X) and np.array_equal(m.quads, q)
    with pytest.raises(InputError, match="no quad or triangle"):
        ShellMesh.from_meshio(meshio.Mesh(X, [("line", [[0, 1]])]))


# --------------------------------------------------------------------------- scikit-fem
def _skfem_area(mesh, element):
    from skfem import Basis, Functional

    one = Functional(lambda w: 1.0 + 0.0 * w.x[0])
    return one.assemble(Basis(mesh, element))


def test_to_skfem_quads():
    from skfem import ElementQuad1, MeshQuad1

    X, q = grid(3, 2)
    X[5, :2] += [0.2, 0.1]  # make it irregular
    m = ShellMesh(X, quads=q)
    s = m.to_skfem()
    assert isinstance(s, MeshQuad1)
    assert np.array_equal(s.p.T, X[:, :2]) and np.array_equal(s.t.T, q)
    # skfem integrates the bilinear map exactly (Gauss rule): an independent area check
    assert _skfem_area(s, ElementQuad1()) == pytest.approx(m.area(), rel=1e-13)


def test_to_skfem_triangles():
    from skfem import ElementTriP1, MeshTri1

    X, q = grid(3, 2)
    m = ShellMesh(X, tris=split(q))
    s = m.to_skfem()
    assert isinstance(s, MeshTri1) and np.array_equal(s.p.T, X[:, :2])
    # skfem sorts each triangle's vertex indices (its sort_t default): same nodes, same order of
    # elements, vertex order within an element may differ
    assert np.array_equal(np.sort(s.t.T, axis=1), np.sort(m.tris, axis=1))
    assert _skfem_area(s, ElementTriP1()) == pytest.approx(6.0, rel=1e-13)  # rounding only


def test_to_skfem_rejects_mixed_and_curved():
    X, q = grid(3, 2)
    with pytest.raises(InputError, match="mixed"):
        ShellMesh(X, quads=q[:4], tris=split(q[4:])).to_skfem()
    with pytest.raises(InputError, match="flat"):
        mixed_curved_mesh().to_skfem()
