"""A scene's ``[perturbation]``: a seeded starting state that steers a drape towards another state.

Drape is multi-stable (paper §3.3-3.4, §4.2: 4, 8, 10 or 12 folds for one sheet).  A run that
starts from the flat sheet follows one symmetric path; a small out-of-plane starting displacement
breaks that symmetry so that the run can settle in another equilibrium.  The perturbation is a
*starting state* U0 (the solver's ``U0``), not an imperfection of the geometry: the equilibrium a
run reaches is one of the unperturbed model.

    [perturbation]
    shape = "random"        # "random": a smooth random field; "folds": cos(n (theta - phase))
    amplitude = 0.5         # [cm] largest out-of-plane starting displacement (0: no perturbation)
    seed = 3                # random: the field's seed (same seed, same field, on every machine)
    wavelength = 5.0        # random: shortest wavelength [cm] (default a quarter of the sheet's span)
    folds = 12              # folds: the number of folds around the pedestal centre
    phase = 0.0             # folds: angle of the first crest [deg] from the warp (global X)

The field w(x, y) [cm] is tapered by (d / d_max)^2, d the distance to the nearest supported node,
so it vanishes with its slope at clamped edges, and scaled so that max |w| = amplitude.  The
starting state moves each node by w along its director X_n (Eq. 1: U_o = w X_n) and turns the
director with the surface, X_n + U_n = unit(X_n - grad_t w) (grad_t: the gradient in the tangent
plane), so the start carries no transverse shear strain (Eq. 12) and little membrane strain.
"""

from __future__ import annotations

from typing import Literal, Optional

import numpy as np
from pydantic import Field, model_validator

from .errors import InputError
from .settings import Finite, SettingsModel, parse

__all__ = ["PerturbationSettings", "parse_perturbation", "initial_state", "N_MODES"]

N_MODES = 24
"""Plane waves summed in the random field: enough for a field without a dominant direction,
few enough to stay smooth at the chosen wavelength."""


class PerturbationSettings(SettingsModel):
    """The ``[perturbation]`` table of a scene (lengths in cm, angles in degrees)."""

    shape: Literal["random", "folds"] = "random"
    amplitude: Finite = Field(0.0, ge=0.0, description="largest starting displacement [cm]")
    seed: int = Field(0, ge=0)
    wavelength: Optional[Finite] = Field(None, gt=0.0, description="random: shortest wavelength [cm]")
    folds: Optional[int] = Field(None, ge=1, le=90)
    phase: Finite = Field(0.0, description="folds: angle of the first crest [deg]")

    @model_validator(mode="after")
    def _shape_keys(self):
        if self.shape == "folds" and self.folds is None:
            raise ValueError("perturbation.shape = 'folds' needs perturbation.folds (the fold count)")
        if self.shape == "random" and self.folds is not None:
            raise ValueError("perturbation.folds applies to shape = 'folds', not 'random'")
        if self.shape == "folds" and self.wavelength is not None:
            raise ValueError("perturbation.wavelength applies to shape = 'random', not 'folds'")
        return self


def parse_perturbation(table: dict | None, where: str = "perturbation") -> PerturbationSettings:
    """The typed ``[perturbation]`` table; InputError (one line, naming the key) if invalid."""
    return parse(PerturbationSettings, table, where)


def _taper(xy: np.ndarray, anchor_xy: np.ndarray) -> np.ndarray:
    """(d / d_max)^2 with d the distance to the nearest anchor point (1 everywhere without one)."""
    if len(anchor_xy) == 0:
        return np.ones(len(xy))
    from scipy.spatial import cKDTree

    d, _ = cKDTree(anchor_xy).query(xy)
    dmax = float(d.max())
    return (d / dmax) ** 2 if dmax > 0.0 else np.zeros(len(xy))


def _field(p: PerturbationSettings, X: np.ndarray, anchors: np.ndarray, centre, span: float):
    """w(points) [unscaled] as a closure over the settings; points (P,3)."""
    if p.shape == "folds":
        c = np.asarray(centre, float)[:2]
        ph = np.radians(p.phase)

        def base(x):
            th = np.arctan2(x[:, 1] - c[1], x[:, 0] - c[0])
            return np.cos(p.folds * (th - ph))
    else:
        rng = np.random.default_rng(p.seed)
        lam_min = p.wavelength if p.wavelength is not None else span / 4.0
        k_lo, k_hi = 2.0 * np.pi / span, 2.0 * np.pi / lam_min
        k_hi = max(k_hi, k_lo)
        kmag = rng.uniform(k_lo, k_hi, N_MODES)
        ang = rng.uniform(0.0, 2.0 * np.pi, N_MODES)
        kv = np.column_stack([kmag * np.cos(ang), kmag * np.sin(ang)])
        amp = rng.standard_normal(N_MODES)
        phase = rng.uniform(0.0, 2.0 * np.pi, N_MODES)

        def base(x):
            return np.cos(x[:, :2] @ kv.T + phase) @ amp

    def w(x):
        return base(x) * _taper(x[:, :2], anchors)

    return w


def initial_state(settings, mesh, fixed, centre=None) -> np.ndarray | None:
    """The (N,6) starting state U0 [cm] of a ``[perturbation]`` on ``mesh`` (None when amplitude 0).

    fixed  : (N,6) bool support mask; nodes with fixed translations anchor the taper
    centre : (x, y[, z]) the folds turn about (the pedestal's centre); required for shape 'folds'
    """
    p = parse_perturbation(settings)
    if p.amplitude == 0.0:
        return None
    if p.shape == "folds" and centre is None:
        raise InputError(
            "perturbation.shape = 'folds' needs a pedestal or sphere to turn about; "
            "this scene has none (use shape = 'random')"
        )
    X = np.asarray(mesh.nodes, float)
    Xn = np.asarray(mesh.directors, float)
    anchor = np.asarray(fixed, bool).reshape(len(X), 6)[:, :3].all(axis=1)
    lo, hi = X[:, :2].min(0), X[:, :2].max(0)
    span = float(np.hypot(*(hi - lo))) or 1.0
    w = _field(p, X, X[anchor, :2], centre, span)
    w0 = w(X)
    peak = float(np.abs(w0).max())
    if not peak > 0.0:
        raise InputError("perturbation: the field vanishes on every free node (is every node supported?)")
    scale = p.amplitude / peak
    # gradient in the plane by central differences of the analytic field (h: 1e-5 of the span,
    # well inside the field's shortest wavelength and far above round-off)
    h = 1e-5 * span
    g = np.zeros_like(X)
    for j in range(2):
        e = np.zeros(3)
        e[j] = h
        g[:, j] = (w(X + e) - w(X - e)) / (2.0 * h)
    g *= scale
    g_t = g - np.sum(g * Xn, axis=1, keepdims=True) * Xn
    n_new = Xn - g_t
    n_new /= np.linalg.norm(n_new, axis=1, keepdims=True)
    U = np.zeros((len(X), 6))
    U[:, :3] = (scale * w0)[:, None] * Xn
    U[:, 3:] = n_new - Xn
    U[np.asarray(fixed, bool).reshape(len(X), 6)] = 0.0
    return U
