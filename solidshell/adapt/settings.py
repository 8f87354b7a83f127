"""Settings of the adaptive procedure (§5.5): one typed schema, checked before any work.

A scene file's ``[adapt]`` table (or ``--adaptive`` and ``--set adapt.KEY=VALUE`` on the command
line) is parsed into :class:`AdaptSettings`; the criteria constants' defaults live with the
criteria (``solidshell.adapt.criteria``) and are imported, not repeated.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from ..settings import Finite, SettingsModel, parse
from .background import MAX_LEVELS
from .criteria import DEFAULT_CONST, DEFAULT_EPS, GUARD_OFF, check_thresholds
from .transition import DEFAULT_TRANSITIONS, TRANSITION_POLICIES


class AdaptSettings(SettingsModel):
    """Reversible 1-to-4 adaptive subdivision inside a dynamic run (paper §5).

    enabled   : run adaptively (``--adaptive``)
    levels    : n, the number of 1-to-4 splittings of the level-0 mesh (§5.1; 3 in the paper)
    const     : the dimensionless threshold of Eq. (25), split where ||eps_b|| L_i > const
    eps       : the hysteresis of Eq. (26), merge where every sibling has ||eps_b|| L_(i-1) <= const - eps
    every     : integration steps between two adaptive passes (§5.5 c); a remesh costs about as much
                as a few hundred steps, so passes are kept a thousand steps apart (docs/adaptivity.md)
    travel    : a pass also comes earlier, at a multiple of min(every, 100) steps, when the fastest
                node at its current speed travels more than ``travel`` times the finest elements'
                smallest side within those steps (a falling sheet is remeshed as often as it needs:
                ``every`` steps are 0.08 s on the paper's path but 8 ms of a free fall at unscaled masses)
    merge_hold : leaves made by a split are not merged back for this many multiples of ``every``
                steps (Eq. 26 vetoed): a creeping sheet otherwise splits, merges and splits the same
                leaves again, each remesh disturbing it (docs/adaptivity.md); 0 (the default) turns
                the hold off
    transfer  : new mid-edge nodes by the discrete-Kirchhoff condition (Eqs. 27-34, "dk") or by linear
                interpolation ("linear", for comparison); centre nodes always by the 8-node serendipity
                functions
    project_boundary : place new nodes on a curved boundary (a circular sheet or rim) on the true curve
    settle_directors : after each transfer, put the director dofs of both time levels at equilibrium
                with the positions (settle.py); False keeps the bare DK directors of Eq. (32)
    settle_scope : "changed" (the default: only the directors of the nodes of elements the pass made,
                the rest held, at the cost of the elements around them) or "all" (every director of
                the sheet, at the cost of the whole tangent; docs/adaptivity.md)
    settle_new_nodes : settle the positions of the inserted nodes with the directors (from the DK
                placement, their neighbours held): the membrane stretch a DK mid-edge node on the cubic
                leaves, and the out-of-balance force and oscillation that follow, go
                (docs/adaptivity.md); where it falls short of three digits the directors alone are
                settled.  Unset: on in relaxation runs (a path to a static state), off in explicit
                dynamics, where a falling sheet is not in static equilibrium and the new nodes'
                inertia is part of the motion
    coarse_membrane : "scene" (every quad has the scene's ``model.membrane``) or "ans" (quads below
                the finest level, transition patches included, take the assumed membrane strains,
                free of the membrane locking that stiffens large elements; docs/adaptivity.md)
    freeze_leaves : 0 (the default) keeps §5.5's procedure, a pass every ``every`` steps to the end.
                K > 0: once the run's time is past ``freeze_after`` [s], the first pass that would
                split between 1 and K leaves and merge none is not made, and the mesh stays as it is
                for the rest of the run.  Each pass kicks the sheet, and a relaxation reaches its
                steady state only once they stop; pair it with a lower ``const``, since the late
                splits carry the drape's last few per cent (docs/adaptivity.md, the freeze tables)
    freeze_after : [s] simulated time before which ``freeze_leaves`` does not stop the passes
    freeze_on : what ``freeze_leaves`` counts in a pass: "splits" (the default: 1-K splits and no
                merge) or "changes" (1-K splits and merges together: a mesh whose passes keep
                splitting here and merging there, as square-on-disc's, never has a pass without a
                merge; docs/adaptivity.md)
    transitions : "fewest_nodes" (the default: transition patches of one and three refined sides,
                patterns 1 and 4, take a variant without the centre node wherever one is valid, one
                node and one element fewer each, at smaller angles) or "quality" (every patch takes
                its pattern's variant furthest from degenerate, which on a square parent uses the
                centre node; transition.py, docs/adaptivity.md)
    guard_alignment : the interpenetration guard: split a leaf where a corner's n_p . d_p (Section 4.3:
                negative where the sheet passes through itself) falls below this value, whatever
                Eq. (25) says, and keep four siblings apart until each reads cos(acos(value) / 2)
                or more (criteria.guard).  Its passes go on past a freeze (splits only).  -1 (the
                default) turns it off; 0.8 (37 degrees between a corner's normal and its director)
                with one guard level keeps large-square-pedestal's folding ears free of
                interpenetration at three levels, in another state than finer meshes reach
                (docs/adaptivity.md; the scene's table takes four levels instead)
    guard_levels : levels beyond ``levels`` that only the guard may split into (the background mesh
                has levels + guard_levels); Eq. (25), the full membrane of ``coarse_membrane`` and
                the pass schedule's finest side keep to ``levels``
    ramp      : coarse-to-fine sequencing (nested iteration) in a relaxation: Eq. (25) may split up
                to level 1 only until the relaxation reaches a loose steady state (its tolerances
                times ``ramp_factor``), then up to level 2, and so on; only the last stage, up to
                ``levels``, relaxes to the run's own steady criterion (and pays the finest
                elements' critical step).  The coarse stages carry the flat sheet to its folded shape
                on a few hundred elements at a larger step (docs/adaptivity.md, "Coarse to fine").
                Relaxations only (a dynamic run's motion is not a path to be shortened): refused in
                explicit dynamics
    ramp_factor : a stage below ``levels`` is steady at ``ramp_factor`` x tol_residual and
                ``ramp_factor``**2 x tol_kinetic (kinetic energy goes as the square of the
                out-of-balance amplitude), with no contact update (contact_augment = 0)

    The background mesh itself refuses a level count whose memory estimate exceeds half of the
    available memory (``background.estimate_background_bytes``), with the estimate.
    """

    enabled: bool = False
    levels: int = Field(3, ge=1, le=MAX_LEVELS)
    const: Finite = Field(DEFAULT_CONST, gt=0.0)
    eps: Finite = Field(DEFAULT_EPS, gt=0.0)
    every: int = Field(1000, ge=1)
    travel: Finite = Field(0.25, gt=0.0)
    merge_hold: int = Field(0, ge=0)
    transfer: Literal["dk", "linear"] = "dk"
    project_boundary: bool = True
    settle_directors: bool = True
    settle_scope: Literal["changed", "all"] = "changed"
    settle_new_nodes: bool | None = None
    coarse_membrane: Literal["scene", "ans"] = "scene"
    freeze_leaves: int = Field(0, ge=0)
    freeze_after: Finite = Field(0.0, ge=0.0)
    freeze_on: Literal["splits", "changes"] = "splits"
    transitions: Literal[TRANSITION_POLICIES] = DEFAULT_TRANSITIONS
    guard_alignment: Finite = Field(GUARD_OFF, ge=GUARD_OFF, lt=1.0)
    guard_levels: int = Field(0, ge=0, le=MAX_LEVELS)
    ramp: bool = False
    ramp_factor: Finite = Field(10.0, ge=1.0)

    @model_validator(mode="after")
    def _hysteresis(self):
        check_thresholds(self.const, self.eps)  # the criteria's own rule: 0 < eps < const
        return self

    @model_validator(mode="after")
    def _total_levels(self):
        if self.levels + self.guard_levels > MAX_LEVELS:
            raise ValueError(f"levels + guard_levels = {self.levels + self.guard_levels} exceeds {MAX_LEVELS}")
        return self

    @property
    def total_levels(self) -> int:
        """Levels of the background mesh: Eq. (25)'s and the guard's."""
        return self.levels + self.guard_levels


def parse_adapt(table: dict | None, where: str = "adapt") -> AdaptSettings:
    """:class:`AdaptSettings` from a scene's ``[adapt]`` table (one-line InputError if invalid)."""
    return parse(AdaptSettings, table, where)
