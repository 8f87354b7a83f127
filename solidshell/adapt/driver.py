"""The adaptive meshing procedure of §5.5 inside a dynamic run (explicit or relaxation).

    a. background mesh from the level-0 mesh (background.py)        b. level 0 switched on
    c. Integrator.advance(every)                                     d. mark by Eqs. (25)-(26)
    e. split / merge (2:1 balanced, transition elements), new nodes by the DK condition
    f. a new problem on the new mesh (masses, loads, critical step)  g. back to c.

The driver knows the solver only through the integrator's small interface (``advance``,
``state``, ``from_state``, ``energies``) and the scene only through ``make_problem(mesh)`` (with
``coarse_quads=`` a per-quad mask when ``adapt.coarse_membrane = "ans"``); the
solvers never import this package.  A new node's position comes from the DK condition (§5.4) and its
velocity (the step increment D_n - D_n-1) from linear / serendipity interpolation; friction anchors
follow the background nodes (a new node starts with no stick anchor).  The energy the transfer adds or removes is booked by the integrator
as ``remesh_energy_jump`` (a new ledger segment at each mesh change), so the balance check stays
honest; the driver also lists each remesh's jump.
"""

from __future__ import annotations

import json
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..errors import InputError
from ..problem import SolveResult, no_progress
from ..solvers.blas import single_threaded_blas
from ..solvers.explicit import Integrator, checkpoint, parse_settings, threads_for
from .background import BackgroundMesh
from .criteria import GUARD_OFF, Marks, guard, leaf_alignment, leaf_bending_strain, level_side_lengths, mark
from .forest import ActiveMesh, AdaptiveMesh
from .settings import AdaptSettings
from .settle import DirectorSettler
from .transfer import to_new_mesh

_STATE_PREFIX = "adapt_"
#: adapt keys whose default changed when they were added: how runs before the key behaved
_BEFORE_KEY = {"transitions": "quality"}
_CHECK_STEPS = 100  # steps between two looks at the sheet's speed (adapt.travel)
_PHASES = ("mark", "mesh", "problem", "transfer", "settle", "integrator")
_REMESH_KEYS = (
    "t",
    "step",
    "splits",
    "merges",
    "nodes_in",
    "nodes_out",
    "active_nodes",
    "energy_jump",
    "kinetic_before",
)


@dataclass
class Segment:
    """One mesh of the run: valid from simulated time t0 [s] (step0) until the next remesh; ``leaves``
    is the leaf state that rebuilds it (kept in checkpoints while a kept frame lies on this mesh)."""

    t0: float
    step0: int
    active: ActiveMesh
    leaves: dict


@dataclass
class AdaptiveOutput:
    """What :func:`run_adaptive` returns: the solver's result on the final mesh, that mesh, and the
    time series on the meshes of their own times: ``series`` = [(t, ShellMesh, U (N,6))]."""

    result: SolveResult
    mesh: object
    series: list = field(default_factory=list)
    active: ActiveMesh | None = None


class AdaptiveRun:
    """One adaptive dynamic run.  ``integrator_cls`` is the explicit Integrator (its from_state
    continues a state on a new problem)."""

    def __init__(
        self,
        level0,
        make_problem,
        integrator_cls,
        settings,
        adapt: AdaptSettings,
        *,
        relax: bool,
        curves=None,
        progress=no_progress,
        restart=None,
    ):
        self.make_problem, self.cls, self.settings, self.adapt = make_problem, integrator_cls, settings, adapt
        self.relax, self.progress = relax, _monotone(progress or no_progress)
        if adapt.ramp and not relax:
            raise InputError("adapt.ramp sequences a relaxation (--solver relax); an explicit run's motion is not")
        self.bg = BackgroundMesh.from_level0(
            level0, adapt.total_levels, curves if adapt.project_boundary else None, adapt.transitions
        )
        self.L = level_side_lengths(self.bg)
        self.forest = AdaptiveMesh(self.bg)
        self.segments: list[Segment] = []
        self.history = []  # (t, active nodes, elements) after every mesh change and at the start
        self.remeshes = []  # per remesh: t, splits, merges, nodes in/out, energy jump
        self.remesh_seconds = 0.0
        self.phase_seconds = dict.fromkeys(_PHASES, 0.0)  # remeshing time by phase (the profile's rows)
        # per level: the step at which each element was made a leaf by a split (-1: never), for
        # adapt.merge_hold
        self.born = [np.full(self.bg.n_elements(l), -1, dtype=np.int64) for l in range(self.bg.levels + 1)]
        # per level: leaves made by a split the guard alone asked for (adapt.guard_alignment), never
        # merged again: a fold's n_p . d_p need not recover on the finer mesh (docs/adaptivity.md)
        self.by_guard = [np.zeros(self.bg.n_elements(l), dtype=bool) for l in range(self.bg.levels + 1)]
        self.settle_failures = 0  # director settlings whose residual did not fall by three digits
        self.new_node_fallbacks = 0  # remeshes whose new-node settling fell short (directors only)
        self.pushed_out = 0  # inserted nodes placed inside a contact body and moved to its surface
        self.frozen = None  # (t, step) at which adapt.freeze_leaves stopped the passes
        self.integ = None
        self.restart_path = restart
        # the step whose pass was last looked at (-1: none).  Checkpoints are written inside
        # Integrator.advance, before the driver looks at that step's pass: a restart at a pass step
        # the checkpoint did not look at takes that look first, as the uninterrupted run did
        self.looked = -1
        # adapt.ramp: the finest level Eq. (25) may split to in this stage (levels: no ramp, or its
        # last stage), and per stage change (t, step, new cap, active nodes before its pass)
        self.cap = 1 if adapt.ramp else adapt.levels
        self.stages: list[tuple[float, int, int, int]] = []

    # ------------------------------------------------------------------ start / restart
    def _problem(self, act: ActiveMesh):
        """The scene's problem on an active mesh; with ``coarse_membrane = "ans"`` the quads below
        the finest level (transition patches included) get the assumed membrane strains."""
        if self.adapt.coarse_membrane == "scene":
            return self.make_problem(act.mesh)
        nq = len(act.mesh.quads)
        coarse = act.elem_leaf[:nq, 0] < self.adapt.levels
        ans = np.zeros(act.mesh.n_elements, dtype=np.int8)
        ans[:nq] = coarse
        act.mesh.cell_tags["assumed_membrane"] = ans  # written with the fields (solidshell/fields.py)
        return self.make_problem(act.mesh, coarse_quads=coarse)

    def start(self) -> None:
        act = self.forest.active_mesh()
        integ = self.cls(self._problem(act), self._stage_settings(), self.progress, relax=self.relax)
        self._enter(integ, act)

    def restart(self, path) -> None:
        """Continue from a checkpoint written by this driver (bit for bit: the saved step, no new
        ledger segment); the meshes of the kept frames are rebuilt from their saved leaf states."""
        state, extra = checkpoint.load(path)
        if _STATE_PREFIX + "segments" not in extra:
            raise InputError(f"restart file {path} was not written by an adaptive run")
        for i, (t0, step0) in enumerate(np.asarray(extra[_STATE_PREFIX + "segments"]).reshape(-1, 2)):
            pre = f"{_STATE_PREFIX}s{i}_"
            leaves = {k[len(pre) :]: v for k, v in extra.items() if k.startswith(pre)}
            forest = AdaptiveMesh.from_state_arrays(self.bg, leaves)
            self.segments.append(Segment(float(t0), int(step0), forest.active_mesh(), leaves))
        self.history = [(float(t), int(n), int(m)) for t, n, m in extra[_STATE_PREFIX + "history"]]
        self.remeshes = [
            dict(
                zip(
                    _REMESH_KEYS,
                    (
                        float(x) if k in ("t", "energy_jump", "kinetic_before") else int(x)
                        for k, x in zip(_REMESH_KEYS, row)
                    ),
                )
            )
            for row in extra[_STATE_PREFIX + "remeshes"]
        ]
        self.remesh_seconds = float(extra[_STATE_PREFIX + "remesh_seconds"])
        for l, b in enumerate(self.born):
            b[:] = np.asarray(extra.get(f"{_STATE_PREFIX}born_{l}", b), dtype=np.int64)
        for l, g in enumerate(self.by_guard):
            g[:] = np.asarray(extra.get(f"{_STATE_PREFIX}guard_{l}", g), dtype=bool)
        phases = np.asarray(extra.get(_STATE_PREFIX + "phase_seconds", np.zeros(len(_PHASES))), dtype=float)
        self.phase_seconds = dict(zip(_PHASES, map(float, phases)))
        # a checkpoint without it (written before the key) was written inside advance: not looked at
        self.looked = int(np.asarray(extra.get(_STATE_PREFIX + "looked", -1)))
        frozen = np.asarray(extra.get(_STATE_PREFIX + "frozen", np.zeros(0)), dtype=float)
        counters = np.asarray(extra.get(_STATE_PREFIX + "counters", np.zeros(3)), dtype=np.int64)
        self.settle_failures, self.new_node_fallbacks, self.pushed_out = map(int, counters)
        self.frozen = (float(frozen[0]), int(frozen[1])) if frozen.size == 2 else None
        # a checkpoint without the key was written before adapt.ramp: every stage was the last
        self.cap = int(np.asarray(extra.get(_STATE_PREFIX + "cap", self.adapt.levels)))
        stages = np.asarray(extra.get(_STATE_PREFIX + "stages", np.zeros((0, 4))), dtype=float).reshape(-1, 4)
        self.stages = [(float(t), int(n), int(c), int(k)) for t, n, c, k in stages]
        self.forest = AdaptiveMesh.from_state_arrays(self.bg, self.segments[-1].leaves)
        act = self.segments[-1].active
        self._check_same_adapt(extra, path)
        integ = self.cls.resume(
            self._problem(act), state, self._stage_settings(), source=path, progress=self.progress, relax=self.relax
        )
        self._enter(integ, act, new_segment=False)

    def _adapt_key(self) -> dict:
        return {k: v for k, v in self.adapt.as_dict().items() if k != "enabled"}

    def _check_same_adapt(self, extra, path) -> None:
        """A restart continues the run that wrote the checkpoint: its adaptive settings too."""
        now = json.loads(json.dumps(self._adapt_key()))
        # a key the checkpoint lacks is one added since it was written: that run behaved as the
        # key's first default, which is its default today unless _BEFORE_KEY says otherwise
        defaults = json.loads(json.dumps({k: v for k, v in type(self.adapt)().as_dict().items() if k in now}))
        saved = {**defaults, **_BEFORE_KEY, **json.loads(str(extra.get(_STATE_PREFIX + "settings", "{}")))}
        diff = sorted(k for k in set(saved) | set(now) if saved.get(k) != now.get(k))
        if diff:
            raise InputError(
                f"restart file {path} was written with other adaptive settings: "
                + ", ".join(f"adapt.{k} {saved.get(k)!r} -> {now.get(k)!r}" for k in diff)
            )

    def _enter(self, integ, act: ActiveMesh, new_segment: bool = True) -> None:
        self.integ, self.active = integ, act
        st = integ.state
        if new_segment:
            self.segments.append(Segment(st.t, st.step, act, self.forest.state_arrays()))
            self.history.append((float(st.t), int(act.mesh.n_nodes), int(act.mesh.n_elements)))
        integ.checkpoint_extra = self._checkpoint_arrays

    def _counters(self):
        """The run's remeshing counters a checkpoint carries (the summary's settle and push-out counts)."""
        return self.settle_failures, self.new_node_fallbacks, self.pushed_out

    def _checkpoint_arrays(self) -> dict:
        """The segments that kept frames lie on (and the current one), each with its leaf state."""
        frames = self.integ.state
        used = {self._segment_of(t, U) for t, U in zip(frames.frame_t, frames.frame_U)}
        used.add(len(self.segments) - 1)
        keep = sorted(used)
        out = {
            _STATE_PREFIX + "segments": np.array([[self.segments[i].t0, self.segments[i].step0] for i in keep]),
            _STATE_PREFIX + "history": np.array(self.history, dtype=float).reshape(-1, 3),
            _STATE_PREFIX + "remeshes": np.array(
                [[r[k] for k in _REMESH_KEYS] for r in self.remeshes], dtype=float
            ).reshape(-1, len(_REMESH_KEYS)),
            _STATE_PREFIX + "remesh_seconds": np.asarray(self.remesh_seconds),
            _STATE_PREFIX + "phase_seconds": np.array([self.phase_seconds[k] for k in _PHASES]),
            _STATE_PREFIX + "settings": np.asarray(json.dumps(self._adapt_key(), sort_keys=True)),
            _STATE_PREFIX + "frozen": np.array(self.frozen if self.frozen is not None else [], dtype=float),
            _STATE_PREFIX + "counters": np.array(self._counters(), dtype=np.int64),
            _STATE_PREFIX + "looked": np.asarray(self.looked, dtype=np.int64),
            _STATE_PREFIX + "cap": np.asarray(self.cap, dtype=np.int64),
            _STATE_PREFIX + "stages": np.array(self.stages, dtype=float).reshape(-1, 4),
            **{f"{_STATE_PREFIX}born_{l}": b.copy() for l, b in enumerate(self.born)},
            **{f"{_STATE_PREFIX}guard_{l}": g.copy() for l, g in enumerate(self.by_guard)},
        }
        for j, i in enumerate(keep):
            out.update({f"{_STATE_PREFIX}s{j}_{k}": v for k, v in self.segments[i].leaves.items()})
        return out

    # ------------------------------------------------------------------ the loop (§5.5 c-g)
    @single_threaded_blas
    def run(self) -> AdaptiveOutput:
        """Steps c-g of §5.5 until the integrator stops (t_end, steady state, a failure, Ctrl-C)."""
        wall0 = time.perf_counter()
        if self.integ is None:
            with self._threads(self.bg.level0):  # the first critical-step estimate included
                self.restart(self.restart_path) if self.restart_path else self.start()
        check = self._check
        step = self.integ.state.step
        if step > 0 and step % check == 0 and self.looked != step:
            # restarted from a checkpoint written at a look step before the look (bit for bit):
            # advance(0) ends an advance there as the uninterrupted run's did (the ledger's end
            # readings a remesh closes its segment with), then the look
            with self._threads(self.active.mesh):
                self.integ.advance(0)
                self._look()
        while True:
            with self._threads(self.active.mesh):  # 1 thread on small meshes, remeshing included
                status = self.integ.advance(check - self.integ.state.step % check)
                if status == "steady" and self.cap < self.adapt.levels:
                    self._next_stage()  # adapt.ramp: steady on this stage's meshes, one level finer
                    continue
                if status != "running":
                    break
                self._look()
        out = self._output()
        wall = time.perf_counter() - wall0
        out.result.info["adaptive_wall_time_s"] = float(wall)
        out.result.info["remesh_share"] = float(self.remesh_seconds / wall) if wall > 0 else 0.0
        return out

    def _look(self) -> None:
        """At a multiple of ``_check`` steps: the adaptive pass when one is due (§5.5 d-f)."""
        if (self.frozen is None or self._guarded) and self._pass_due():
            t0 = time.perf_counter()
            self._adapt_pass()
            self.remesh_seconds += time.perf_counter() - t0
        self.looked = self.integ.state.step

    def _stage_settings(self):
        """The relaxation's settings for the current stage of adapt.ramp: the run's own on the last
        stage (and without a ramp); below it the steady tolerances loosened by ``ramp_factor``
        (residual x f, kinetic energy x f^2) and no contact update, since the stage's state is only
        the start of the next, finer one (as the static sequence's COARSE_TOLERANCES)."""
        s = self.settings
        if self.cap >= self.adapt.levels:
            return s
        f = float(self.adapt.ramp_factor)
        return s.model_copy(
            update={"tol_residual": s.tol_residual * f, "tol_kinetic": s.tol_kinetic * f * f, "contact_augment": 0}
        )

    def _next_stage(self) -> None:
        """adapt.ramp: the relaxation is steady (loosely) at the current cap: allow one level more and
        pass at once; when that pass leaves the mesh as it is, the same state continues on the
        same problem under the next stage's settings (as a restart would: no new ledger segment,
        the critical step kept)."""
        st = self.integ.state
        self.stages.append((float(st.t), int(st.step), self.cap + 1, int(self.active.mesh.n_nodes)))
        self.cap += 1
        t0 = time.perf_counter()
        self._adapt_pass(may_freeze=False)
        if self.integ.status != "running":  # no new mesh: this integrator stopped at the stage's steady state
            old = self.integ
            self.integ = self.cls.from_state(
                old.problem,
                st,
                self._stage_settings(),
                reestimate_step=False,
                new_segment=False,
                progress=self.progress,
                relax=self.relax,
            )
            self._carry(old)
            self._enter(self.integ, self.active, new_segment=False)
        self.remesh_seconds += time.perf_counter() - t0
        self.looked = st.step

    def _carry(self, old) -> None:
        """The run's counters and warnings from the integrator ``old`` to its successor."""
        self.integ.restarted_from = old.restarted_from
        self.integ.steps_done, self.integ.t_loop = old.steps_done, old.t_loop
        self.integ.wall0 = old.wall0
        self.integ.warnings = old.warnings

    @property
    def _h_fine(self) -> float:
        """Smallest side of the finest level Eq. (25) may split to now (``levels``, or a ramp's cap)."""
        return float(np.min(self.L[self.cap]))

    @property
    def _check(self) -> int:
        """Steps between two looks at the sheet's speed (and the only steps a pass can fall on)."""
        return min(self.adapt.every, _CHECK_STEPS)

    def _pass_due(self) -> bool:
        """A pass at every multiple of ``every`` steps, and earlier, at a multiple of ``_check``, when
        the fastest node at its current speed travels more than ``adapt.travel`` times the finest
        elements' smallest side within ``_check`` steps.  Both depend on the state at this step
        only, so a restart keeps the schedule (bit for bit)."""
        st = self.integ.state
        if st.step % self.adapt.every == 0:
            return True
        d = (st.D - st.D_prev).reshape(-1, 6)[:, :3]
        step = float(np.sqrt(np.max(np.einsum("ij,ij->i", d, d)))) if len(d) else 0.0
        return step * self._check > self.adapt.travel * self._h_fine

    def _threads(self, mesh):
        """The solver's thread rule (solvers.explicit.threads_for) for a mesh of this size."""
        return threads_for(SimpleNamespace(model=SimpleNamespace(mesh=mesh)), self.settings.threads)

    @contextmanager
    def _timed(self, phase: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.phase_seconds[phase] += time.perf_counter() - t0

    @property
    def _guarded(self) -> bool:
        return self.adapt.guard_alignment > GUARD_OFF

    @property
    def guard_splits(self) -> int:
        """Leaves split by adapt.guard_alignment alone: each made four ``by_guard`` children, and
        those are never merged."""
        return sum(int(np.count_nonzero(g)) for g in self.by_guard) // 4

    def _marks(self):
        """Eqs. (25)-(26) up to ``adapt.levels`` (none past a freeze), then the guard up to the
        background's finest level."""
        st = self.integ.state
        model = self.integ.model
        U = st.D.reshape(-1, 6)
        eb = model.bending_strain(U)
        leaves, eb_leaf = leaf_bending_strain(eb, self.active.elem_leaf)
        if self.frozen is None:
            marks = mark(eb_leaf, leaves, self.L, self.adapt.const, self.adapt.eps, max_level=self.cap)
        else:
            marks = Marks(np.zeros(len(leaves), dtype=bool), np.zeros((0, 2), dtype=np.int64))
        if not self._guarded:
            return marks, leaves, np.zeros(len(leaves), dtype=bool)
        nd = np.concatenate([c.min(axis=1) for c in model.interpenetration(U)])
        _, nd_leaf = leaf_alignment(nd, self.active.elem_leaf)
        guarded = guard(marks, nd_leaf, leaves, self.adapt.guard_alignment, self.bg.levels)
        return guarded, leaves, guarded.split & ~marks.split

    def _adapt_pass(self, may_freeze: bool = True) -> None:
        """Steps d-f: mark, split/merge, and when the mesh changed continue on the new one (past a
        freeze: the guard's splits only).  ``may_freeze`` False: a ramp's stage change, whose pass
        brings the next level and is never the one that freezes the mesh."""
        self.looked = self.integ.state.step
        with self._timed("mark"):
            marks, leaves, guard_only = self._marks()
        merge = self._held(marks.merge)
        n_split = int(np.count_nonzero(marks.split))
        n_merge = len(merge)
        if not n_split and not n_merge:
            return
        if may_freeze and self.frozen is None and self._freezes(n_split, len(marks.merge)):
            st = self.integ.state
            self.frozen = (float(st.t), int(st.step))
            return
        with self._timed("mesh"):
            before = self.forest.state_arrays()
            if n_merge:
                self.forest.merge(merge)
            if n_split:
                self.forest.split(leaves[marks.split])
                self._note_births(before, leaves[guard_only])
            new = self.forest.active_mesh()
        if np.array_equal(new.nodes, self.active.nodes) and _same_leaves(before, self.forest.state_arrays()):
            return
        self._switch(new, n_split, n_merge)

    def _freezes(self, n_split: int, n_merge_marked: int) -> bool:
        """adapt.freeze_leaves: past ``freeze_after``, a pass that would split 1-K leaves and merge
        none (``freeze_on = "splits"``), or change 1-K leaves in all (``"changes"``: splits plus
        merges), stops the passes for the rest of the run (instead of being made)."""
        a = self.adapt
        if a.freeze_leaves <= 0 or self.integ.state.t <= a.freeze_after or self.cap < a.levels:
            return False  # a ramp's coarse stages do not freeze: the finer levels are still to come
        if a.freeze_on == "changes":
            return n_split + n_merge_marked <= a.freeze_leaves
        return n_merge_marked == 0 and n_split <= a.freeze_leaves

    def _held(self, parents):
        """The merges of Eq. (26) less those whose children a split made within the last
        ``merge_hold * every`` steps, and those whose children the guard made."""
        hold = self.adapt.merge_hold * self.adapt.every
        if not len(parents) or not (hold or self._guarded):
            return parents
        parents = np.asarray(parents, dtype=np.int64).reshape(-1, 2)
        step = self.integ.state.step
        keep = np.ones(len(parents), dtype=bool)
        for l in np.unique(parents[:, 0]):
            sel = np.flatnonzero(parents[:, 0] == l)
            kids = 4 * parents[sel, 1][:, None] + np.arange(4)
            born = self.born[l + 1][kids]
            keep[sel] = ~(((born >= 0) & (born > step - hold)) | self.by_guard[l + 1][kids]).any(axis=1)
        return parents[keep]

    def _note_births(self, before: dict, by_guard) -> None:
        """Record the step at which each leaf made by this pass's splits appeared, and which of them
        the guard alone asked for (the children of the (level, index) parents ``by_guard``)."""
        step = self.integ.state.step
        for l in range(1, self.bg.levels + 1):
            was_leaf_parent = np.asarray(before[f"leaf_{l - 1}"], dtype=bool)
            made = self.forest.leaf[l] & np.repeat(was_leaf_parent, 4)  # children of a parent split now
            self.born[l][made] = step
        by_guard = np.asarray(by_guard, dtype=np.int64).reshape(-1, 2)
        for l in np.unique(by_guard[:, 0]):
            parents = by_guard[by_guard[:, 0] == l, 1]
            self.by_guard[l + 1][(4 * parents[:, None] + np.arange(4)).ravel()] = True

    def _switch(self, new: ActiveMesh, n_split: int, n_merge: int) -> None:
        old, integ = self.active, self.integ
        st = integ.state
        v = (st.D - st.D_prev) / st.dt  # half-step velocity: no force evaluation needed
        kinetic_before = 0.5 * float(np.add.reduce(integ.Mf * v * v))
        Nb = len(self.bg.Xo)
        inserted = np.setdiff1d(new.nodes, old.nodes, assume_unique=True)
        with self._timed("problem"):
            problem = self._problem(new)
        with self._timed("transfer"):
            st.D, st.D_prev = self._transfer(st.D, st.D_prev, old, new)
            _impose_prescribed(problem, st.D, st.D_prev)
            st.anchors = _remap_anchors(st.anchors, old.nodes, new.nodes, Nb)
            if np.any(st.mode):  # the top mode, interpolated: Lanczos' start on the new mesh
                st.mode = to_new_mesh(self.bg, st.mode, old.nodes, new.nodes, "linear", "serendipity")
        if self.adapt.settle_directors:
            with self._timed("settle"):
                st.D, st.D_prev = self._settle(problem, st.D, st.D_prev, new, inserted)
        with self._timed("transfer"):
            self.pushed_out += _outside_bodies(
                problem, new.mesh.nodes, st.D, st.D_prev, np.searchsorted(new.nodes, inserted)
            )
        jump0 = st.remesh_energy_jump
        # every new mesh gets its own critical step: a pass that adds no finer level can still make
        # stiffer elements (transition patches at a graded level 0's corners; docs/adaptivity.md)
        with self._timed("integrator"):
            self.integ = self.cls.from_state(
                problem, st, self._stage_settings(), reestimate_step=True, progress=self.progress, relax=self.relax
            )
        self._carry(integ)
        self.remeshes.append(
            dict(
                t=float(st.t),
                step=int(st.step),
                splits=n_split,
                merges=n_merge,
                nodes_in=int(len(inserted)),
                nodes_out=int(len(np.setdiff1d(old.nodes, new.nodes, assume_unique=True))),
                active_nodes=int(new.mesh.n_nodes),
                energy_jump=float(self.integ.state.remesh_energy_jump - jump0),
                kinetic_before=kinetic_before,
            )
        )
        self._enter(self.integ, new)

    def _transfer(self, D, Dp, old: ActiveMesh, new: ActiveMesh):
        """(D_n, D_n-1) on the new mesh.  Positions of new nodes by the chosen transfer (§5.4: DK);
        their step increment D_n - D_n-1 (the velocity) by linear / serendipity interpolation of
        their neighbours', a convex combination that cannot exceed them.  DK applied to D_n-1 too
        (the paper's "similar approach") would map the fast velocities of the light directors,
        through w_oM = -L/8 (v_nA - v_nB), into translational velocities of heavy nodes
        (docs/adaptivity.md)."""
        D_new = to_new_mesh(self.bg, D, old.nodes, new.nodes, self.adapt.transfer, "kirchhoff")
        step = to_new_mesh(self.bg, D - Dp, old.nodes, new.nodes, "linear", "serendipity")
        return D_new, D_new - step

    def _settle(self, problem, D, Dp, new: ActiveMesh, inserted):
        """D_n's directors put at equilibrium with its positions (settle.py), and D_n-1 one
        quasi-static step behind: the directors' velocity becomes the rate at which their
        equilibrium follows the transferred velocity of every position, which drops the director
        oscillation the previous remeshes' out-of-balance forces left in the velocity (keeping that
        velocity is not enough, and settling D_n-1 apart leaves the two settlings' residual errors
        in the velocity: docs/adaptivity.md).  With ``adapt.settle_new_nodes`` the inserted nodes'
        positions settle too (from their DK placement, the old nodes held), but keep their
        interpolated velocity: the quasi-static rate of a position, -K_SS^-1 K_SH v, is unbounded
        where K_SS nearly loses definiteness (a hoop-compressed sheet near buckling: 70 cm/s for a
        sheet moving at 4, docs/adaptivity.md).  Where that settling falls short of its three digits
        (large new elements sag far from their DK placement), the directors alone are settled
        instead and ``new_node_fallbacks`` counts it."""
        region = _changed_nodes(self.active, new) if self.adapt.settle_scope == "changed" else None

        def both(nodes=None):
            settler = DirectorSettler(problem.model, problem.loads, problem.fixed, nodes, region)
            D_s, rep = settler(D, max_iter=_SETTLE_ITER_NEW if nodes is not None else _SETTLE_ITER)
            if nodes is not None:  # the directors' rate only: the new nodes keep their interpolated step
                settler = DirectorSettler(problem.model, problem.loads, problem.fixed, None, region)
            return D_s, D_s - settler.quasi_static_step(D_s, D - Dp), int(not rep.converged)

        if self._settle_new_nodes and len(inserted):
            D_s, Dp_s, short = both(np.searchsorted(new.nodes, inserted))
            if not short:
                return D_s, Dp_s
            self.new_node_fallbacks += 1  # not settled: the new nodes keep their DK placement
        D_s, Dp_s, short = both()
        self.settle_failures += short
        return D_s, Dp_s

    @property
    def _settle_new_nodes(self) -> bool:
        """adapt.settle_new_nodes; unset: on for relaxation, off for explicit dynamics."""
        return self.relax if self.adapt.settle_new_nodes is None else bool(self.adapt.settle_new_nodes)

    # ------------------------------------------------------------------ output
    def _output(self) -> AdaptiveOutput:
        res = self.integ.result()
        res.info.update(self.summary_info())
        series = self._series(res.frames)
        return AdaptiveOutput(result=res, mesh=self.active.mesh, series=series, active=self.active)

    def _segment_of(self, t: float, U) -> int:
        """Index of the segment a kept frame (t, U) lies on: the last one started at or before t
        whose mesh has U's node count (a frame at a remesh time was kept on the mesh before it)."""
        n = np.asarray(U).size // 6
        for i in range(len(self.segments) - 1, -1, -1):
            s = self.segments[i]
            if s.t0 <= t + 1e-12 and s.active.mesh.n_nodes == n:
                return i
        raise RuntimeError(f"no mesh of this run has {n} nodes at t = {t} s")  # a bug, not user input

    def _series(self, frames) -> list:
        return [
            (float(t), self.segments[self._segment_of(t, U)].active.mesh, np.asarray(U).reshape(-1, 6))
            for t, U in frames
        ]

    def summary_info(self) -> dict:
        counts = [h[1] for h in self.history]
        return {
            "adaptive": True,
            "adapt_levels": int(self.adapt.levels),
            "adapt_const": float(self.adapt.const),
            "adapt_eps": float(self.adapt.eps),
            "adapt_every": int(self.adapt.every),
            "adapt_travel": float(self.adapt.travel),
            "adapt_merge_hold": int(self.adapt.merge_hold),
            "adapt_transfer": self.adapt.transfer,
            "adapt_settle_directors": bool(self.adapt.settle_directors),
            "adapt_settle_scope": self.adapt.settle_scope,
            "adapt_settle_new_nodes": self._settle_new_nodes,
            "adapt_coarse_membrane": self.adapt.coarse_membrane,
            "adapt_freeze_leaves": int(self.adapt.freeze_leaves),
            "adapt_freeze_after": float(self.adapt.freeze_after),
            "adapt_freeze_on": self.adapt.freeze_on,
            "adapt_transitions": self.adapt.transitions,
            "adapt_guard_alignment": float(self.adapt.guard_alignment),
            "adapt_guard_levels": int(self.adapt.guard_levels),
            "guard_splits": int(self.guard_splits),
            "adapt_ramp": bool(self.adapt.ramp),
            "adapt_ramp_factor": float(self.adapt.ramp_factor),
            "ramp_stages": [dict(t=t, step=n, cap=c, nodes_before=k) for t, n, c, k in self.stages],
            "remesh_frozen_at": None if self.frozen is None else {"t": self.frozen[0], "step": self.frozen[1]},
            "settle_failures": int(self.settle_failures),
            "settle_new_node_fallbacks": int(self.new_node_fallbacks),
            "remesh_nodes_pushed_out": int(self.pushed_out),
            "level0_elements": int(self.bg.n_elements(0)),
            "background_nodes": int(len(self.bg.Xo)),
            "max_active_nodes": int(max(counts)),
            "final_active_nodes": int(counts[-1]),
            "active_nodes_history": [[round(t, 6), n, m] for t, n, m in self.history],
            "remesh_count": len(self.remeshes),
            "remesh_time_s": float(self.remesh_seconds),
            "remesh_phase_s": {k: round(v, 4) for k, v in self.phase_seconds.items()},
            "remesh_energy_jumps": [r["energy_jump"] for r in self.remeshes],
            "remeshes": self.remeshes,
            "max_level_reached": int(max(s.active.elem_leaf[:, 0].max() for s in self.segments)),
        }


def _monotone(cb):
    """A progress callback whose fraction never goes back (each new mesh's integrator starts its
    own estimate from zero)."""
    best = [0.0]

    def call(fraction, text=""):
        best[0] = max(best[0], float(fraction))
        cb(best[0], text)

    return call


_SETTLE_ITER = 8
"""Newton steps of a directors-only settling (they converge in 2-5)."""
_SETTLE_ITER_NEW = 30
"""Newton steps when the inserted nodes' positions settle too: a DK mid-edge node of a large, bent
element sits ~0.1-0.3 cm off where its half-edges are unstretched, and the backtracked steps take
10-30 iterations to bring it there (square-on-disc's first remesh: 29).  Stopping at 8 fell back to
directors only and left the stretch: 8.9 gf cm booked there instead of 1.5 (docs/adaptivity.md)."""


def _impose_prescribed(problem, D, Dp) -> None:
    """The prescribed values (clamps: zero) on both time levels of the new mesh's fixed dofs, in
    place.  A node inserted on a clamped edge is transferred like any other (DK places it on the
    bent edge's cubic, ~1e-2 cm off the clamp); the integrator would snap it back in one step, a
    velocity of (offset / 2 dt) ~ 50 cm/s on the clamp that the first ledger reading books as energy."""
    fx = np.asarray(problem.fixed, dtype=bool).ravel()
    pv = np.asarray(problem.prescribed, dtype=float).ravel()
    D[fx] = pv[fx]
    Dp[fx] = pv[fx]


_SETTLE_RINGS = 2
"""Element rings around the new elements whose directors settle with theirs (adapt.settle_scope =
"changed").  None: the kick spreads past the settled patch (square-pedestal, paper path to t = 8 s:
energy balance error 1.7e-2 instead of 3.9e-4, 22 % more nodes); two: the same run as settling
every director (5.2e-4, DC within 0.15 %) at 0.6 of its settling time (docs/adaptivity.md)."""


def _changed_nodes(old: ActiveMesh, new: ActiveMesh) -> np.ndarray:
    """Indices (in ``new``'s numbering) of the nodes of the elements of ``new`` that ``old`` does not
    have (an element is its set of background nodes), and of the _SETTLE_RINGS rings of elements
    around them."""
    changed = np.zeros(new.mesh.n_nodes, dtype=bool)
    for a, b in ((old.mesh.quads, new.mesh.quads), (old.mesh.tris, new.mesh.tris)):
        if not len(b):
            continue
        rows_b = np.sort(new.nodes[b], axis=1)
        rows_a = np.sort(old.nodes[a], axis=1).reshape(-1, b.shape[1])
        fresh = ~_rows_in(rows_b, rows_a)
        changed[b[fresh].ravel()] = True
    for _ in range(_SETTLE_RINGS):
        ring = changed.copy()
        for b in (new.mesh.quads, new.mesh.tris):
            if len(b):
                ring[b[changed[b].any(axis=1)].ravel()] = True
        changed = ring
    return np.flatnonzero(changed)


def _rows_in(rows, table) -> np.ndarray:
    """(K,) bool: each row of ``rows`` (K,k) is a row of ``table`` (J,k) (non-negative ints).  Rows
    as 1-d keys in base max + 1 when those fit in int64 (np.unique over rows sorts a structured
    view, ~10x slower), else by that unique."""
    if not len(rows) or not len(table):
        return np.zeros(len(rows), dtype=bool)
    base = int(max(rows.max(), table.max())) + 1
    k = rows.shape[1]
    if base**k < 2**63:
        w = base ** np.arange(k - 1, -1, -1, dtype=np.int64)
        return np.isin(rows.astype(np.int64) @ w, table.astype(np.int64) @ w)
    _, inv = np.unique(np.vstack([table, rows]), axis=0, return_inverse=True)
    inv = inv.ravel()
    return np.isin(inv[len(table) :], inv[: len(table)])


def _same_leaves(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def _outside_bodies(problem, X, D, Dp, idx) -> int:
    """Move the nodes ``idx`` that lie inside a contact body (closer to it than its offset) onto its
    offset surface, along its normal, on both time levels alike (their velocity kept), in place;
    returns how many moved.  Contact acts at the nodes only, so a body can stand through a large
    element between its nodes, and the nodes a split inserts there land inside it, where the first
    step's penalty forces throw them out (docs/adaptivity.md, "Inserted nodes inside a contact
    body")."""
    if not len(idx) or not problem.contact:
        return 0
    U, Up = D.reshape(-1, 6), Dp.reshape(-1, 6)
    fixed = np.asarray(problem.fixed, dtype=bool)[idx, :3].any(axis=1)
    idx = np.asarray(idx)[~fixed]
    moved = np.zeros(len(idx), dtype=bool)
    for body in problem.contact:
        gap, n = body.penetration(X[idx] + U[idx, :3])
        inside = gap < 0.0
        shift = -gap[inside, None] * n[inside]
        U[idx[inside], :3] += shift
        Up[idx[inside], :3] += shift
        moved |= inside
    return int(np.count_nonzero(moved))


def _remap_anchors(anchors, old_nodes, new_nodes, Nb):
    """Friction anchors (n_fric, N_old, 3) -> (n_fric, N_new, 3) by background node; new nodes NaN
    (no stick anchor yet: the return map starts them sticking where they touch)."""
    a = np.asarray(anchors)
    if a.size == 0 and a.shape[0] == 0:
        return np.zeros((0, len(new_nodes), 3))
    full = np.full((a.shape[0], Nb, 3), np.nan)
    full[:, old_nodes] = a
    return full[:, new_nodes]


def run_adaptive(
    level0,
    make_problem,
    settings,
    adapt: AdaptSettings,
    *,
    relax: bool,
    curves=None,
    progress=no_progress,
    restart=None,
) -> AdaptiveOutput:
    """Run an adaptive explicit (``relax=False``) or relaxation (``relax=True``) drape from the
    level-0 mesh ``level0``; ``make_problem(mesh) -> Problem`` poses the scene on any active mesh
    (and accepts ``coarse_quads=`` (n_quads,) bool, the quads to give "ans" membranes, when
    ``adapt.coarse_membrane = "ans"``)."""
    return AdaptiveRun(
        level0,
        make_problem,
        Integrator,
        parse_settings(settings, relax),
        adapt,
        relax=relax,
        curves=curves,
        progress=progress,
        restart=restart,
    ).run()
