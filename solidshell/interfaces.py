"""The declared interfaces between the library's parts (typing.Protocol): what a solver may use of a
problem and its model, what a contact body offers, what a damper and an observer of the explicit
solver get.  Code that receives one of these objects uses its declared members only -- no
``hasattr`` probing -- and tells capabilities apart by ``isinstance`` on a declared type:

* the library's :class:`solidshell.model.Model` (mesh, element blocks, compiled passes, tangent) or
  any :class:`ExplicitModel` (a user's or a test's stand-in: force, energy and masses only);
* a :class:`QuasiStrainModel` (runtime-checkable): a model with Eq. (24)'s quasi thickness strain,
  whose energy jumps where n_p.d_p crosses -mu, so the energy ledger books those jumps.

Nothing here runs; the concrete classes live beside what they implement (``problem.Problem``,
``contact.RigidBody``, ``solvers.explicit.damping.Damper``, ``solvers.explicit.integrator``'s view
of a run for its damper, ``solvers.explicit.observers``).  Arrays: dofs flat (6N,) as in Eq. (1)
unless (N, 6) is said; lengths in the model's unit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # annotations only: importing these here would import the solvers
    import scipy.sparse as sp

    from .solvers.explicit.kernels import Dofs
    from .solvers.explicit.settings import RelaxSettings
    from .solvers.explicit.state import State


# ----------------------------------------------------------------------------- models
class ExplicitModel(Protocol):
    """What the explicit solver needs of any model: (N,6) displacements U in, (N,6) or flat forces
    out.  The library's Model has all of this and more (the solver then takes its compiled path)."""

    n_nodes: int

    def lumped_mass(self) -> np.ndarray:
        """(N,6) lumped nodal masses."""

    def internal_force(self, U) -> np.ndarray:
        """Internal force F(U), (N,6) or flat."""

    def energy(self, U) -> float:
        """Strain energy at U."""


class ElementBlock(Protocol):
    """One block of elements of a model: its connectivity (M, nodes per element)."""

    conn: np.ndarray


@runtime_checkable
class QuasiStrainModel(Protocol):
    """A model whose thickness strain may be Eq. (24)'s quasi-engineering one (``quasi``): its energy
    jumps where n_p.d_p crosses -mu at an element corner; ``interpenetration(U)`` gives n_p.d_p per
    block, (M, corners) in the order of ``blocks``."""

    n_nodes: int
    quasi: bool
    mu: float
    blocks: Sequence[ElementBlock]

    def interpenetration(self, U) -> list[np.ndarray]:
        """n_p.d_p per element corner, one (M, corners) array per block."""


# ----------------------------------------------------------------------------- contact
class ContactBody(Protocol):
    """A rigid contact body (solidshell.contact.RigidBody and its subclasses): a solid given by its
    signed distance, positive outside, with the outward unit normal.  ``code`` >= 0 names the
    compiled distance of contact_kernels (with ``params``), -1 a user's body, whose
    ``signed_distance`` the laws call instead.  ``lipschitz``: a bound on |g(x) - g(y)| / |x - y|,
    None when unknown (then every node is a contact candidate)."""

    offset: float  # distance kept between the body and the mid-surface [length]
    friction: float  # Coulomb coefficient mu (0: frictionless)
    lipschitz: float | None
    code: int

    @property
    def params(self) -> np.ndarray:
        """(contact_kernels.PARAMS,) the body's numbers for the compiled kernels."""

    @property
    def curvature_radius(self) -> float | None:
        """Radius of the most curved smooth face [length], None for flat faces or unknown."""

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g (m,), n (m,3)) at points x (m,3)."""

    def given_distances(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The distances the compiled laws take as given: empty for code >= 0."""

    def penetration(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(gap = g - offset (m,), normal (m,3)) at points x (m,3)."""

    def forces(self, x: np.ndarray, k) -> tuple[np.ndarray, float]:
        """(penalty forces (m,3), penalty energy) at points x with stiffness k (scalar or (m,))."""

    def active(self, x: np.ndarray) -> np.ndarray:
        """(m,) bool: the points in contact."""


# ----------------------------------------------------------------------------- problems
class SolverProblem(Protocol):
    """What a solver needs of a posed problem (solidshell.problem.Problem)."""

    model: ExplicitModel
    fixed: np.ndarray  # (N,6) bool: prescribed dofs
    loads: np.ndarray  # (N,6) dead nodal forces [force]
    prescribed: np.ndarray  # (N,6) values of the prescribed dofs [length]
    contact: Sequence[ContactBody]  # empty: no contact search at all
    name: str


# ----------------------------------------------------------------------------- explicit solver
class DampingView(Protocol):
    """What a damper (solvers/explicit/damping) sees of the run it damps -- not the integrator: the
    settings, the dof arrays, the state it books into, and the few operations a damper performs on
    the scheme (change the step, change the viscous alpha, redo the step, the stiffness)."""

    settings: RelaxSettings
    dofs: Dofs

    @property
    def state(self) -> State:
        """The run's state (D_n, dt, the damper's fields fire_a/fire_n/damper_alpha, damp_sum, ...)."""

    @property
    def fresh(self) -> bool:
        """True on a run started from its initial state (not continued from another's)."""

    @property
    def step_power(self) -> tuple[float, float, float] | None:
        """(R.v_n, v_n.M.v_n, R.M^-1.R) of this step when the fused step formed them, else None."""

    @property
    def dt_crit(self) -> float:
        """The critical step of the current estimate [s]."""

    def time_of(self, n: int) -> float:
        """Simulated time [s] of step n."""

    def change_step(self, n: int, dt: float) -> None:
        """The steps from t_n on are dt (t_n stays where it is)."""

    def set_alpha(self, alpha: float) -> None:
        """The viscous alpha [1/s] of Eq. (23) from now on (kept in the state)."""

    def central_step(self, Dn1, D, Dp, R) -> tuple[float, bool]:
        """Eq. (23) with the current coefficients into Dn1: (v_n.M.v_n, D_n+1 finite)."""

    def stiffness(self, D) -> sp.csr_matrix:
        """(6N, 6N) stiffness at D: the model's tangent plus the contact and stick springs."""


class Damper(Protocol):
    """A damping mode of dynamic relaxation (solvers/explicit/damping/__init__.py says when each hook
    runs).  The flags are declared by every damper (the base class's defaults: False)."""

    name: str
    rewrites_step: bool  # correct() computes D_n+1 from R alone (the fused step only forms R)
    wants_power: bool  # correct() reads view.step_power
    varies_alpha: bool  # the viscous alpha changes during the run (state.damper_alpha)

    def alpha0(self, settings) -> float:
        """The viscous alpha [1/s] at the start."""

    def correct(self, view: DampingView, n: int, D, Dp, Dn1, R, vMv: float) -> tuple[float, bool]:
        """After the step D_n -> D_n+1, before its books: (v_n.M.v_n for the books, finite)."""

    def after(self, view: DampingView, n: int, D, Dn1, R, vMv: float) -> None:
        """After the books, before the state advances."""


class Observer(Protocol):
    """Something that watches a run without changing it (solvers/explicit/observers.py: checkpoints,
    progress): asked after every step whether it is due -- an integer or clock comparison."""

    def due(self, step: int) -> bool:
        """True when it wants to act after step ``step``."""


class RunReadings(Protocol):
    """The latest readings of a run a progress report shows (the explicit State has them)."""

    last_ekin: float  # kinetic energy at the last sample
    last_rel_res: float  # |R|_free / |P|_free at the last check
    last_rel_ke: float  # E_kin / W_ext at the last check


class FrameStore(Protocol):
    """The kept frames of a run (the explicit State's): times, (N,6) displacements, interval index
    (-1: not an interval frame) and the frame interval [s]."""

    frame_t: list
    frame_U: list
    frame_k: list
    frame_dt: float
