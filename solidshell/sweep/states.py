"""Distinct equilibria of a sweep: runs grouped into states, with each state's frequency.

A drape is multi-stable (paper §3.3-3.4, §4.2): one sheet settles with 4, 8, 10 or 12 folds.  Two
runs are taken to be the same equilibrium when

* their fold counts agree (solidshell.analysis.fold_count),
* their drape coefficients differ by at most ``dc_tol``, and
* their projected boundaries, as radius profiles r(theta) about the pedestal centre, differ by at
  most ``boundary_tol`` x the mean radius at every angle once the second is mapped by the best
  element of the problem's symmetry group (a state and its mirror image or its quarter turn are
  one state when the sheet, the pedestal and the fabric are symmetric that way).

The symmetry group (``symmetry_group``): the geometry's -- D4 (the square's eight rotations and
mirrors) for a square sheet, O2 (every rotation and mirror) for a disc on a disc -- restricted by
an orthotropic fabric (warp and weft rigidities differ, as for the paper's wool) to the elements
that map the warp direction onto itself (so D2 about the warp for wool: rotation by 180 deg and the
mirrors in the warp and weft).  ``symmetry`` in [classify] overrides it.

Grouping is deterministic: runs in sweep order, each joins the first state whose representative
(its first run) it matches, else starts a new state.  Runs that did not converge (or lack a drape
profile) are counted apart, as "unsettled".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .ledger import PROFILE_POINTS

__all__ = ["symmetry_group", "group_elements", "fingerprint", "profile_distance", "classify", "State"]

GROUPS = ("C1", "C2", "D2", "D4", "O2")


def symmetry_group(scene) -> str:
    """The group of a scene (a solidshell.scenes.Scene), as ``NAME@ANGLE``: geometry group
    intersected with the fabric's (D2 about the warp when warp and weft differ)."""
    r = scene.recipe
    geo = {"square_on_square": "D4", "square_on_disc": "D4", "square": "D4", "disc_on_disc": "O2"}.get(r, "C1")
    if geo == "C1":
        return "C1@0"
    m = scene.material_object()
    Cm, Cb = np.asarray(m.C_m, float), np.asarray(m.C_b, float)
    warp = math.degrees(float(m.warp_angle_rad))  # Fabric's angle; 0 for an IsotropicShell

    def differs(C):
        return abs(C[0, 0] - C[1, 1]) > 1e-9 * max(abs(C[0, 0]), abs(C[1, 1]), 1e-300)

    if not (differs(Cm) or differs(Cb)):
        return f"{geo}@0"
    if geo == "O2":
        return f"D2@{warp:g}"
    # D4 restricted to the elements that keep the warp axis (mod 180 deg)
    keep = [(s, phi) for s, phi in _elements("D4", 0.0) if _keeps_axis(s, phi, warp)]
    if len(keep) == 8:
        return "D4@0"
    if len(keep) == 4:
        return f"D2@{warp:g}"
    return "C2@0"


def _keeps_axis(s, phi, a) -> bool:
    d = ((s - 1) * a + phi) % 180.0
    return min(d, 180.0 - d) < 1e-6


def _elements(name: str, axis: float, step: float = 360.0 / PROFILE_POINTS):
    """[(s, phi)]: theta -> s theta + phi [deg] for each group element."""
    if name == "C1":
        return [(1, 0.0)]
    if name == "C2":
        return [(1, 0.0), (1, 180.0)]
    if name == "D2":  # rotations 0, 180; mirrors in the axis a and its normal: theta -> 2a - theta (+180)
        return [(1, 0.0), (1, 180.0), (-1, (2 * axis) % 360.0), (-1, (2 * axis + 180.0) % 360.0)]
    if name == "D4":
        return [(s, float(k * 90 + (2 * axis if s < 0 else 0.0)) % 360.0) for s in (1, -1) for k in range(4)]
    if name == "O2":
        n = int(round(360.0 / step))
        return [(s, k * step) for s in (1, -1) for k in range(n)]
    raise ValueError(f"unknown symmetry group {name!r} (known: {', '.join(GROUPS)})")


def group_elements(group: str):
    """Elements of ``NAME@ANGLE`` (or a bare NAME: axis 0) as [(s, phi_deg)]."""
    name, _, ax = group.partition("@")
    return _elements(name, float(ax or 0.0))


def _index_maps(group: str, n: int = PROFILE_POINTS) -> np.ndarray:
    """(G, n) indices: row g gives r(g^-1 theta_j) for the profile grid theta_j = j 360/n deg."""
    j = np.arange(n)
    rows = []
    for s, phi in group_elements(group):
        # (g r)(theta) = r(g^-1 theta), g^-1 theta = s (theta - phi)
        k = np.rint(phi * n / 360.0).astype(int)
        rows.append((s * (j - k)) % n)
    return np.asarray(rows)


def profile_distance(r1, r2, group: str = "C1") -> float:
    """min over the group of max_theta |r1 - g r2| / mean(r1) (dimensionless)."""
    r1 = np.asarray(r1, float)
    r2 = np.asarray(r2, float)
    idx = _index_maps(group, len(r1))
    d = np.abs(r2[idx] - r1[None, :]).max(axis=1)
    return float(d.min() / max(r1.mean(), 1e-300))


def fingerprint(fold_count, fold_angles_deg, dc, group: str = "C1") -> str:
    """A run's state label: ``<n>f:<canonical angles>:DC<dc>``, the fold angles rounded to 5 deg
    and taken in the lexicographically smallest form over the group (the same state seen rotated
    or mirrored gives the same label, up to the rounding)."""
    if fold_count is None or dc is None or not np.isfinite(dc):
        return "unsettled"
    a = np.asarray(fold_angles_deg or [], float)
    best = None
    name = group.partition("@")[0]
    elems = group_elements(group) if name != "O2" else None
    if name == "O2":  # every rotation: put each fold at 0 in turn, both mirrors
        cands = []
        for s in (1, -1):
            b = (s * a) % 360.0
            cands += [np.sort((b - x) % 360.0) for x in b] or [b]
    else:
        cands = [np.sort((s * a + phi) % 360.0) for s, phi in elems]
    for c in cands:
        t = tuple(int(5 * round(x / 5.0)) % 360 for x in c)
        t = tuple(sorted(t))
        best = t if best is None or t < best else best
    angles = "-".join(str(x) for x in (best or ()))
    return f"{int(fold_count)}f:{angles}:DC{float(dc):.2f}"


@dataclass
class State:
    """One distinct equilibrium of a sweep."""

    number: int
    fold_count: int
    representative: dict  # the ledger row of its first run
    members: list = field(default_factory=list)  # ledger rows
    profile: np.ndarray | None = field(default=None, repr=False)  # the representative's r(theta)

    @property
    def count(self) -> int:
        return len(self.members)

    def dc_range(self):
        v = [m["drape_coefficient"] for m in self.members]
        return min(v), float(np.mean(v)), max(v)


def _settled(row) -> bool:
    return (
        row.get("status") == "done"
        and bool(row.get("converged"))
        and row.get("radius_profile") is not None
        and row.get("drape_coefficient") is not None
        and row.get("fold_count") is not None
    )


def classify(rows, dc_tol: float = 0.01, boundary_tol: float = 0.03, group: str = "C1"):
    """(states, unsettled rows) from ledger rows (dicts), grouped as in the module docstring."""
    states: list[State] = []
    unsettled = []
    idx = None
    for row in sorted(rows, key=lambda r: r["index"]):
        if not _settled(row):
            unsettled.append(row)
            continue
        r = np.asarray(row["radius_profile"], float)
        if idx is None:
            idx = _index_maps(group, len(r))
        home = None
        for st in states:
            rep = st.representative
            if rep["fold_count"] != row["fold_count"]:
                continue
            if abs(rep["drape_coefficient"] - row["drape_coefficient"]) > dc_tol:
                continue
            r0 = st.profile
            d = np.abs(r[idx] - r0[None, :]).max(axis=1).min() / max(r0.mean(), 1e-300)
            if d <= boundary_tol:
                home = st
                break
        if home is None:
            home = State(number=len(states) + 1, fold_count=int(row["fold_count"]), representative=row, profile=r)
            states.append(home)
        home.members.append(row)
    return states, unsettled
