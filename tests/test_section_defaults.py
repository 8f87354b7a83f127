"""The paper leaves the transverse shear rigidity C_t, the thickness modulus E_z and the in-plane
Poisson coupling of the fabric unstated (DESIGN.md).  material.Fabric chooses C_t = 5/6 T_mean/2,
E_z = T_mean, nu = 0; these tests show that the drape of the wool strip (Section 3.1) does not
depend on the first two over two decades, and measure the dependence on the coupling."""

import pytest

from solidshell import Fabric, Model, solve_static
from solidshell.boundary import clamp, gravity_loads
from solidshell.meshing import build_mesh


@pytest.fixture(scope="module")
def strip():
    return build_mesh("strip", "10x1")


def tip_z(mesh, fabric):
    model = Model(mesh, fabric)
    res = solve_static(model, clamp(mesh, "clamped"), gravity_loads(model))
    assert res.converged
    tip = mesh.node_set("tip")
    return float((mesh.nodes[tip, 2] + res.U[tip, 2]).mean())


@pytest.mark.parametrize("factor", [0.1, 10.0])
@pytest.mark.parametrize("field", ["transverse_shear", "thickness_modulus"])
def test_drape_independent_of_unstated_rigidities(strip, field, factor):
    base = Fabric.wool()
    default = base.C_t[0, 0] if field == "transverse_shear" else base.E_z
    z0 = tip_z(strip, base)
    z = tip_z(strip, Fabric.wool(**{field: factor * default}))
    # Measured: C_t x0.1 -> 3.2e-4, x10 -> 3.2e-5; E_z x0.1 -> 8.2e-5, x10 -> 8.2e-6 (relative tip
    # change).  Bound 1e-3: below the 20x1 mesh's discretisation error against the elastica
    # (1.2e-3), so the choice of these rigidities is invisible next to the mesh.
    assert abs(z / z0 - 1.0) < 1e-3


def test_poisson_coupling_is_a_small_physical_effect(strip):
    z0 = tip_z(strip, Fabric.wool())
    # with free long edges the coupling lowers the strip's effective bending rigidity to
    # B (1 - nu^2), so it droops further; near the heavy elastica's asymptote the tip moves much
    # less than 9 %: measured 0.93 % at nu = 0.3 and ~0.1 % at nu = 0.1.  It is data a user may
    # supply (KES gives none), not a numerical knob.
    d1 = tip_z(strip, Fabric.wool(poisson=0.1)) / z0 - 1.0
    d3 = tip_z(strip, Fabric.wool(poisson=0.3)) / z0 - 1.0
    assert 0.0 < d1 < 2e-3
    assert 3e-3 < d3 < 2e-2
    assert d3 / d1 == pytest.approx(9.0, rel=0.25)  # quadratic in nu
