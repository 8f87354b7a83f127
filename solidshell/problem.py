"""Problem: everything a solver needs, and nothing about files or scenes.

A solver receives a :class:`Problem` and a plain ``settings`` dict and returns a :class:`SolveResult`.
Dofs follow Eq. (1): per node [U_o (3) | U_n (3)], global index 6*node + k.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np


@dataclass
class Problem:
    """A posed shell problem.

    model      : solidshell.model.Model (mesh + section; energy, force, tangent, mass)
    fixed      : (N,6) bool, True where the dof is prescribed
    loads      : (N,6) dead external nodal forces P [force] (gravity, point, line, surface loads)
    prescribed : (N,6) prescribed values of the fixed dofs [length] (default zero: clamped)
    contact    : rigid contact bodies (solidshell.contact); empty means no contact search at all
    self_contact : whether the sheet's layers push each other apart (contact_self_penalty.py in
                 explicit dynamics and relaxation, contact_self.py in the static solver)
    name       : label used in messages
    """

    model: Any
    fixed: np.ndarray
    loads: np.ndarray
    prescribed: np.ndarray | None = None
    contact: list = field(default_factory=list)
    name: str = "problem"
    self_contact: bool = False

    def __post_init__(self):
        n = self.model.n_nodes
        self.fixed = np.asarray(self.fixed, dtype=bool).reshape(n, 6)
        self.loads = np.asarray(self.loads, dtype=float).reshape(n, 6)
        if self.prescribed is None:
            self.prescribed = np.zeros((n, 6))
        else:
            self.prescribed = np.asarray(self.prescribed, dtype=float).reshape(n, 6)

    @property
    def free(self) -> np.ndarray:
        """Flat indices of the free dofs."""
        return np.flatnonzero(~self.fixed.ravel())


@dataclass(repr=False)
class SolveResult:
    """What a solver returns (its repr is one line: converged, the state's size and the message).

    U         : (N,6) final displacements
    converged : whether the solver met its own convergence / steady-state criterion
    message   : one line saying how it ended (why it stopped, when it did not converge)
    info      : plain JSON-able numbers for summary.json (iterations, linear_solves, residual, ...)
    frames    : list of (time or load factor, (N,6) U) kept for output (time series, load path)
    path      : the same list, by the static solver's name for it (each converged load step or
                arc-length point)
    """

    U: np.ndarray
    converged: bool
    message: str = ""
    info: dict = field(default_factory=dict)
    frames: list = field(default_factory=list)

    @property
    def path(self) -> list:
        return self.frames

    def __repr__(self) -> str:
        U = np.asarray(self.U)
        size = "x".join(map(str, U.shape))
        umax = ""
        if U.ndim and U.size and U.size % 6 == 0 and np.all(np.isfinite(U)):
            umax = f", max |U_o| {float(np.max(np.linalg.norm(U.reshape(-1, 6)[:, :3], axis=1))):.4g}"
        msg = " ".join(str(self.message or "").split())
        msg = msg if len(msg) <= 100 else msg[:99] + "..."
        return (
            f"<SolveResult {'converged' if self.converged else 'NOT converged'}, U {size}{umax}, "
            f"{len(self.frames or [])} frame(s), {len(self.info or {})} info keys: {msg!r}>"
        )


Progress = Callable[[float, str], None]
"""progress(fraction_done in [0,1], short status text) -- solvers call it; the CLI draws the bar."""


def no_progress(fraction: float, text: str = "") -> None:
    return None
