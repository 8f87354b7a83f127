"""Which mode sets the explicit critical step of the sheet (Eq. 23), and so what a finer adaptive level
costs in steps (docs/adaptivity.md, "The critical step: thickness mode or membrane mode").

omega_max is the top frequency of M^-1 K at the flat state (matrix-free Lanczos, stepcontrol.omega_sheet)
of a square wool sheet, 10 cm wide, on uniform grids of 2.5 to 0.3125 cm quads."""

from __future__ import annotations

import numpy as np
import pytest

from solidshell import Fabric, ShellMesh
from solidshell.model import Model
from solidshell.solvers.explicit import scaled_mass, stepcontrol
from solidshell.solvers.explicit.settings import parse_settings
from verification.checks.common import rect_grid

WOOL = Fabric.wool()


def grid(n, size=10.0):
    nodes, quads = rect_grid(n, n, size, size)
    return ShellMesh(nodes, quads=quads, directors=np.tile([0.0, 0.0, 1.0], (len(nodes), 1)))


def omega_max(n, **relax):
    s = parse_settings(relax, True)
    mesh = grid(n)
    model = Model(mesh, WOOL)
    M = scaled_mass(model, s.mass_scaling, s.mass_scaling_mode)
    return stepcontrol.omega_sheet(model, M, np.ones((mesh.n_nodes, 6), bool), np.zeros(M.size), s)[0]


def test_with_every_mass_scaled_alike_the_thickness_mode_sets_the_step_at_any_element_size():
    """The paper's premise for adaptivity (§5: "the critical time step is controlled by the thickness
    stretching mode and, in general, is insensitive to the planar size of the element"): with every
    mass scaled alike (the paper's path scales all by 100) omega_max is the same for 2.5 cm and
    0.3125 cm quads (measured 2.3478e5 rad/s unscaled, equal to 1e-13)."""
    w = [omega_max(n, mass_scaling=1.0) for n in (4, 8, 16, 32)]
    assert np.ptp(w) <= 1e-9 * w[0], w


def test_with_heavy_directors_the_membrane_mode_sets_the_step_and_it_halves_with_the_element():
    """Director masses x10^4 (the kinetic and FIRE relaxations' choice) slow the thickness mode by
    100, and the membrane mode, c / h, takes over: measured 6078, 12160, 24310 rad/s for 2.5, 1.25,
    0.625 cm.  Then each finer level halves the step.  Tolerance 5 %: at 0.625 cm the thickness mode
    (23,480) is near, and the two modes mix."""
    w4, w8, w16 = (omega_max(n, mass_scaling=1e4, mass_scaling_mode="director") for n in (4, 8, 16))
    assert w8 == pytest.approx(2.0 * w4, rel=0.05) and w16 == pytest.approx(2.0 * w8, rel=0.05), (w4, w8, w16)
