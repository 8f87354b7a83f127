"""Explicit dynamics (Section 4): central differences with mass-proportional Rayleigh damping,
Eq. (23), and dynamic relaxation (Section 4.2).  The scheme, the critical step, the energy ledger,
friction, Eq. (24) jumps and mass scaling are described, with their measurements, in
docs/explicit.md.

Modules: ``settings`` (typed settings), ``state`` (the integrator state), ``kernels`` (the compiled
step), ``forces`` (internal, contact, friction), ``fused`` (preallocated element and node passes with
the step fused in), ``stepcontrol`` (critical step), ``ledger`` (energy
balance), ``observers`` (frames, checkpoints, progress, steady state), ``checkpoint`` (files and
the run's fingerprint), ``integrator`` (``Integrator``).  ``run`` and ``run_relax`` below are the
drivers the solver registry calls.
"""

from __future__ import annotations

from contextlib import contextmanager

from ...interfaces import SolverProblem
from ...model import Model
from ...problem import Problem, SolveResult, no_progress
from ..blas import single_threaded_blas
from . import checkpoint
from .integrator import Integrator, scaled_mass
from .kernels import central_step as _central_step  # noqa: F401  (the hot loop's compiled step)
from .settings import ExplicitSettings, RelaxSettings, parse_settings
from .state import State

__all__ = [
    "run",
    "run_relax",
    "scaled_mass",
    "SMALL_MESH_ELEMENTS",
    "Integrator",
    "State",
    "checkpoint",
    "ExplicitSettings",
    "RelaxSettings",
]

SMALL_MESH_ELEMENTS = 1000
"""Below this many elements the loop runs the force kernel on one thread by default: a step then
takes microseconds and starting/joining the kernel's worker threads every step costs more than it
saves (the 1- against 2-thread measurements behind the threshold: docs/benchmarks.md, "Threads").
The results are bitwise the same on any number of threads (element forces in parallel, fixed
chunks, one serial sum).  On a machine whose cores are busy with other jobs two threads are much
slower (a worker waits a whole time slice for a core); pass ``threads=1`` there."""


@contextmanager
def threads_for(problem: SolverProblem, threads):
    """Numba threads for the force kernel during the block: ``threads`` (capped at the machine's),
    or 1 below SMALL_MESH_ELEMENTS elements and the current count otherwise; yields the count."""
    import numba

    model = problem.model
    n_elem = model.mesh.n_elements if isinstance(model, Model) else 0  # a model of its own: small
    old = numba.get_num_threads()
    new = (
        (1 if n_elem < SMALL_MESH_ELEMENTS else old)
        if threads is None
        else min(int(threads), numba.config.NUMBA_NUM_THREADS)
    )
    numba.set_num_threads(new)
    try:
        yield new
    finally:
        numba.set_num_threads(old)


def _drive(problem, settings, progress, relax) -> SolveResult:
    s = parse_settings(settings, relax)
    with threads_for(problem, s.threads) as n_threads:
        if s.restart:
            integ = Integrator.resume(problem, checkpoint.load(s.restart)[0], s, source=s.restart, progress=progress)
        else:
            integ = Integrator(problem, s, progress)
        integ.advance()
        res = integ.result()
    res.info["threads"] = int(n_threads)
    return res


@single_threaded_blas
def run(problem: Problem, settings: dict | None = None, progress=no_progress) -> SolveResult:
    """Dynamic drape (Section 4.1): integrate Eq. (23) from t = 0 to ``settings["t_end"]``.
    converged = True when t_end was reached with a finite state.  A Ctrl-C returns the last
    completed step with converged = False and info["status"] = "interrupted"."""
    return _drive(problem, settings, progress, relax=False)


@single_threaded_blas
def run_relax(problem: Problem, settings: dict | None = None, progress=no_progress) -> SolveResult:
    """Dynamic relaxation (Section 4.2): damped explicit dynamics with scaled masses (default α = 5 1/s,
    masses ×100) that stops itself once E_kin / W_ext < tol_kinetic and the relative residual force
    |P - F + C|_free / |P|_free < tol_residual.  ``damping="kinetic"`` uses Cundall's kinetic damping
    (all velocities zeroed at each kinetic-energy peak; ``alpha`` is then ignored: no viscous damping).
    converged = steady_state_reached."""
    return _drive(problem, settings, progress, relax=True)
