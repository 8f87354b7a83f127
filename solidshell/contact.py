"""Penalty contact between the sheet and rigid bodies (Section 4.2: cloth on a sphere, [9]).

Bodies
------
:class:`Sphere`, :class:`Plane` (a floor: the half-space below the plane is solid),
:class:`Pedestal` (a flat-topped vertical cylinder or box with an optional rounded top edge) and
:class:`CusickSupport` (a Cusick-type drape tester's support: a disc on a narrower stem).
Their distances and the laws below are compiled, one node at a time (``contact_kernels``); a
user's own :class:`RigidBody` subclass gives ``signed_distance`` and goes through the same laws.
Each body is a *solid*; its signed distance ``g(x)`` is positive outside, negative inside, and its
``normal`` is the unit outward gradient ``∇g``.

Which points touch
------------------
Contact is enforced on the **mid-surface nodes** only (x = X_o + U_o).  Forces act on the U_o
dofs; the director dofs U_n never see contact.  The sheet's lower face lies h/2 below its
mid-surface; pass ``offset = h/2`` to a body to keep the mid-surface that far off the body (default
0: the mid-surface itself touches).  Edges between nodes are not checked: a body narrower than an
element can slip between nodes (use an element size below the body's smallest radius).

Penalty law
-----------
With the penetration p = max(0, offset - g(x)) of a node, the penalty energy is

    E_c = 1/2 sum_i k_i p_i^2 ,   f_i = -dE_c/dx_i = k_i p_i n(x_i)   (frictionless)

so the force is conservative (it enters the energy balance as stored energy E_c), zero outside the
body, and continuous across the surface.  The force is exactly minus the gradient of E_c wherever the
signed distance is differentiable (everywhere outside; inside a box/pedestal except on the medial
planes where the nearest face changes, where the force has a kink but the energy stays continuous).

Coulomb friction (optional, per body: ``friction`` = mu >= 0, default 0)
--------------------------------------------------------------------------
As in the penalty contacts of LS-DYNA and Abaqus/Explicit: every node in contact with a body of
friction mu carries a tangential elastic "stick" spring of stiffness k_t to an anchor point a_i,
set where the node first touches.  With the tangential part s = (I - n n^T)(x - a) of the spring's
stretch, the trial force -k_t s is return-mapped to the Coulomb cone |f_t| <= mu |f_n|
(|f_n| = k p): inside it the node sticks; outside it the force is scaled onto the cone and the
anchor slides with the node, a := x + f_t / k_t (then the stored stick stretch is exactly |f_t|/k_t).
A node leaving the body forgets its anchor.  The friction force is path dependent: it is not
minus the gradient of an energy; the solver accumulates its work instead (stick energy
1/2 |f_t|^2 / k_t plus dissipation by slip) -- :func:`frictional_contact`.  Its stiffness k_t
(default = the normal penalty k) enters the critical step like k: the contact Hessian of a node
has eigenvalues k (normal) and k_t (tangential), so the bound below uses max(k, k_t).
Bodies with mu = 0 never reach this code (no anchors, no extra work).

Penalty stiffness rule
----------------------
:func:`penalty_stiffness` gives every node the stiffness k_i = factor * m_i * omega_max^2, with m_i
its (possibly mass-scaled) mid-surface mass and omega_max the highest natural frequency of the
sheet (``timestep.critical_time_step``).  A node in contact then vibrates against the body at
sqrt(factor) * omega_max, and by Weyl's inequality the highest frequency of sheet + contact is at
most omega_max * sqrt(1 + factor): the penalty shortens the critical step by the factor
1/sqrt(1 + factor) at most (:func:`contact_critical_time_step`, :func:`combined_critical_time_step`);
with the default factor 0.1 that is 4.7 %.  Because omega_max is the (very high) thickness mode of
the solid-shell, this penalty is very stiff: a node carrying its own weight m_i g sinks
g / (factor * omega_max^2) into the body -- about 2e-7 cm for wool at dt ~ 1e-5 s.  Uniform mass
scaling by s leaves k unchanged (m ×s, omega^2 ÷s).  (The curvature term k p ∇²g of the contact
Hessian is neglected in this bound; it is of relative size p / R and p is tiny.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from . import contact_kernels as ck
from .errors import InputError
from .interfaces import ContactBody

DEFAULT_PENALTY_FACTOR = 0.1
"""Default ``factor`` of :func:`penalty_stiffness` (contact frequency sqrt(0.1) * omega_max)."""

PENETRATION_TOL = 0.02
"""The contact contract's tolerance as a fraction of the sheet's thickness h: no node and no point of
an element's contact face lies deeper than ``PENETRATION_TOL * h`` inside a body (its ``offset``
included: the penetration of a mid-surface point x is ``offset - g(x)``).  2 % of h is 12 um for the
paper's wool (h = 0.0593 cm): far below what a picture or the DC can show, and above the penalty's
own sink under the sheet's weight (~1e-7 cm, :func:`penalty_stiffness`)."""


def _vec3(v, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float).ravel()
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be 3 finite numbers, got {v!r}")
    return a


def friction_coefficient(v, name: str = "friction") -> float:
    """A Coulomb friction coefficient: a finite number >= 0 (0: frictionless)."""
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{name} (Coulomb friction coefficient) must be a number >= 0, got {v!r}") from None
    if not math.isfinite(x) or x < 0.0:
        raise InputError(f"{name} (Coulomb friction coefficient) must be finite and >= 0, got {v!r}")
    return x


def _pos(v, name: str, allow_zero=False) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {v!r}") from None
    if not math.isfinite(x) or x < 0.0 or (x == 0.0 and not allow_zero):
        raise InputError(f"{name} must be {'non-negative' if allow_zero else 'positive'}, got {v!r}")
    return x


def _params(*values) -> np.ndarray:
    out = np.zeros(ck.PARAMS)
    out[: len(values)] = values
    return out


class RigidBody:
    """Base class (the interface the solvers use: solidshell.interfaces.ContactBody; every member
    is declared here).  The bodies here set ``code`` and ``params`` (the compiled distances of
    ``contact_kernels``); a user's subclass implements :meth:`signed_distance` -> (g (N,), n (N,3))
    instead, and gets the same penalty and friction laws.

    ``lipschitz``: a bound L on |g(x) - g(y)| / |x - y| (1 for an exact distance, as for every body
    here), or None when unknown.  With it the explicit solver checks contact only at the nodes
    within a margin of the body and re-selects them once any node has moved margin / L."""

    offset: float = 0.0
    friction: float = 0.0  # Coulomb coefficient mu (0: frictionless, the default)
    lipschitz: float | None = None

    code: int = -1  # contact_kernels.SPHERE, PLANE, CYLINDER, BOX, CUSICK or MESH; -1: a user's body
    grid: np.ndarray | None = None  # a MESH body's distance samples (contact_mesh.py); None: the others

    @property
    def curvature_radius(self) -> float | None:
        """The radius of the body's most curved smooth face [length] (sharp edges not counted), None
        when it has none (flat faces) or it is unknown: how closely face points must sit
        (contact_faces.spacing)."""
        return None

    @property
    def params(self) -> np.ndarray:
        """(contact_kernels.PARAMS,) the body's numbers for the kernels, from its attributes now."""
        return np.zeros(ck.PARAMS)

    def signed_distance(self, x: np.ndarray):
        """(g (N,), n (N,3)): signed distance of the points x (N,3), positive outside, and the
        outward unit normal (contact_kernels.signed_distance; a subclass of code < 0 overrides this)."""
        if self.code < 0:  # pragma: no cover - interface
            raise NotImplementedError
        return ck.distances(self.code, self.params, np.ascontiguousarray(x, dtype=float).reshape(-1, 3), self.grid)

    def given_distances(self, x):
        """(g_in, n_in) for contact_kernels.body_forces: empty for the bodies the kernels know, the
        signed distances of the points x otherwise."""
        if self.code >= 0:
            return ck._G0, ck._N0
        g, n = self.signed_distance(x)
        return np.ascontiguousarray(g, dtype=float), np.ascontiguousarray(n, dtype=float).reshape(-1, 3)

    def penetration(self, x):
        """(gap (N,), normal (N,3)) for points x (N,3): gap = g(x) - offset, negative when the point
        is closer to the body than ``offset`` (in contact); normal = outward unit normal ∇g."""
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        g, n = self.signed_distance(x)
        return g - self.offset, n

    def forces(self, x, k):
        """Penalty forces (N,3) on the points x (N,3) and the penalty energy (float).

        k : scalar or (N,) penalty stiffness [force/length] (see :func:`penalty_stiffness`).
        """
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        f = np.zeros_like(x)
        kk = np.ascontiguousarray(np.broadcast_to(np.asarray(k, dtype=float), (len(x),)))
        e, _, _, _, _ = ck.body_forces(
            self.code, self.params, self.offset, 0.0, x, kk, kk, f, f, f, f, *self.given_distances(x), self.grid
        )
        return f, e

    def active(self, x) -> np.ndarray:
        """(N,) bool: points in contact (gap < 0)."""
        return self.penetration(x)[0] < 0.0


class Sphere(RigidBody):
    """Rigid solid sphere of ``radius`` about ``center`` (the paper's Ø10 cm sphere, Section 4.2)."""

    lipschitz = 1.0  # |x - c| - R is a distance

    def __init__(self, center, radius, offset=0.0, friction=0.0):
        self.center = _vec3(center, "sphere center")
        self.radius = _pos(radius, "sphere radius")
        self.offset = _pos(offset, "contact offset", allow_zero=True)
        self.friction = friction_coefficient(friction)
        self.code = ck.SPHERE

    @property
    def params(self) -> np.ndarray:
        return _params(*self.center, self.radius)

    @property
    def curvature_radius(self) -> float | None:
        return self.radius

    def __repr__(self):
        return (
            f"Sphere(center={self.center.tolist()}, radius={self.radius}, offset={self.offset}, "
            f"friction={self.friction})"
        )


class Plane(RigidBody):
    """Rigid half-space: the side of the plane through ``point`` opposite to ``normal`` is solid
    (a floor with normal (0,0,1))."""

    lipschitz = 1.0  # (x - p).n with |n| = 1

    def __init__(self, point, normal=(0.0, 0.0, 1.0), offset=0.0, friction=0.0):
        self.point = _vec3(point, "plane point")
        nn = _vec3(normal, "plane normal")
        L = np.linalg.norm(nn)
        if L == 0.0:
            raise InputError("plane normal must be non-zero")
        self.normal = nn / L
        self.offset = _pos(offset, "contact offset", allow_zero=True)
        self.friction = friction_coefficient(friction)
        self.code = ck.PLANE

    @property
    def params(self) -> np.ndarray:
        return _params(*self.point, *self.normal)

    def __repr__(self):
        return (
            f"Plane(point={self.point.tolist()}, normal={self.normal.tolist()}, offset={self.offset}, "
            f"friction={self.friction})"
        )


class Pedestal(RigidBody):
    """A rigid flat-topped pedestal standing on its base: a vertical cylinder or a box.

    Parameters
    ----------
    top_center : (3,) centre of the top face [length]; the pedestal axis is global Z.
    radius : cylinder radius (give this for a circular pedestal), or
    half_widths : (a, b) half side lengths along X and Y (give this for a square/box pedestal).
    height : height below the top face (default: 10 × the top's size; only the top face and the
        top edge matter for a drape).
    edge_radius : rounding radius of the top edge (default 0: sharp edge; the distance outside is
        still the exact distance to the sharp edge, so the outside surface normal turns smoothly
        around it).

    The paper clamps the sheet along the pedestal edge and models only the hanging part, so the
    pedestal body keeps the hanging skirt out of the pedestal's side and top (a pedestal scene
    builds one by default: solidshell.scenes.Scene.bodies).
    """

    # the exact signed distance of a box (Euclidean outside, minus the nearest face's distance
    # inside) is 1-Lipschitz, and so is its composition with the 1-Lipschitz x -> (|x_xy|, z)
    lipschitz = 1.0

    def __init__(
        self, top_center, radius=None, half_widths=None, height=None, edge_radius=0.0, offset=0.0, friction=0.0
    ):
        self.top_center = _vec3(top_center, "pedestal top_center")
        if (radius is None) == (half_widths is None):
            raise InputError("give a pedestal either radius (cylinder) or half_widths (box), not both")
        if radius is not None:
            self.kind = "cylinder"
            self.radius = _pos(radius, "pedestal radius")
            size = self.radius
        else:
            hw = np.asarray(half_widths, dtype=float).ravel()
            if hw.shape != (2,):
                raise InputError(f"pedestal half_widths must be (a, b), got {half_widths!r}")
            self.kind = "box"
            self.half_widths = np.array([_pos(hw[0], "half width a"), _pos(hw[1], "half width b")])
            size = float(self.half_widths.max())
        self.height = _pos(height, "pedestal height") if height is not None else 10.0 * size
        self.edge_radius = _pos(edge_radius, "edge_radius", allow_zero=True)
        if self.edge_radius >= min(size, 0.5 * self.height):
            raise InputError("pedestal edge_radius must be smaller than its radius/half width and half height")
        self.offset = _pos(offset, "contact offset", allow_zero=True)
        self.friction = friction_coefficient(friction)
        self.code = ck.CYLINDER if self.kind == "cylinder" else ck.BOX

    @property
    def curvature_radius(self) -> float | None:
        """The rounded edge and, for a cylinder, its side (a box's faces are flat)."""
        r = [self.edge_radius] if self.edge_radius > 0.0 else []
        if self.kind == "cylinder":
            r.append(self.radius)
        return min(r) if r else None

    @property
    def params(self) -> np.ndarray:
        top = (*self.top_center, self.height, self.edge_radius)
        return _params(*top, self.radius) if self.kind == "cylinder" else _params(*top, *self.half_widths)

    def __repr__(self):
        dims = f"radius={self.radius}" if self.kind == "cylinder" else f"half_widths={self.half_widths.tolist()}"
        return (
            f"Pedestal({self.kind}, top_center={self.top_center.tolist()}, {dims}, height={self.height}, "
            f"edge_radius={self.edge_radius}, offset={self.offset}, friction={self.friction})"
        )


class CusickSupport(RigidBody):
    """The support of a Cusick-type drape tester: a flat disc of ``radius`` and ``disc_thickness``
    on a narrower coaxial stem of ``stem_radius`` that reaches from the disc's underside down to the
    base, ``height`` below the top face (axis global Z).  One body: its signed distance is the
    smaller of the two cylinders' (contact_kernels.CUSICK), the exact distance to the union outside
    it (a skirt hanging under the disc's overhang meets the disc's underside or the stem, whichever
    is nearer) and 1-Lipschitz everywhere.  ``edge_radius`` rounds the disc's top edge (default 0:
    sharp); an upper clamping disc is a second body (a :class:`Pedestal` cylinder on the sheet).
    """

    lipschitz = 1.0  # the minimum of two 1-Lipschitz distances

    def __init__(
        self, top_center, radius, disc_thickness, stem_radius, height=10.0, edge_radius=0.0, offset=0.0, friction=0.0
    ):
        self.top_center = _vec3(top_center, "support top_center")
        self.radius = _pos(radius, "support disc radius")
        self.disc_thickness = _pos(disc_thickness, "support disc_thickness")
        self.stem_radius = _pos(stem_radius, "support stem radius")
        self.height = _pos(height, "support height")
        if self.stem_radius > self.radius:
            raise InputError(
                f"support stem radius ({self.stem_radius:g}) exceeds the disc radius ({self.radius:g}): "
                "a Cusick-type stem must not be wider than its disc"
            )
        if self.disc_thickness >= self.height:
            raise InputError(
                f"support disc_thickness ({self.disc_thickness:g}) must be smaller than its height ({self.height:g})"
            )
        self.edge_radius = _pos(edge_radius, "edge_radius", allow_zero=True)
        if self.edge_radius >= min(self.radius, 0.5 * self.disc_thickness):
            raise InputError("support edge_radius must be smaller than the disc radius and half its thickness")
        self.offset = _pos(offset, "contact offset", allow_zero=True)
        self.friction = friction_coefficient(friction)
        self.code = ck.CUSICK

    @property
    def curvature_radius(self) -> float | None:
        """The disc's and the stem's sides and the rounded edge."""
        r = [self.radius, self.stem_radius] + ([self.edge_radius] if self.edge_radius > 0.0 else [])
        return min(r)

    @property
    def params(self) -> np.ndarray:
        return _params(
            *self.top_center, self.height, self.edge_radius, self.radius, self.disc_thickness, self.stem_radius
        )

    def __repr__(self):
        return (
            f"CusickSupport(top_center={self.top_center.tolist()}, radius={self.radius}, "
            f"disc_thickness={self.disc_thickness}, stem_radius={self.stem_radius}, height={self.height}, "
            f"edge_radius={self.edge_radius}, offset={self.offset}, friction={self.friction})"
        )


# ---------------------------------------------------------------------- all bodies at once
def contact_forces(bodies: Sequence[ContactBody], x, k):
    """Sum over ``bodies`` of the penalty forces on points x (N,3): (forces (N,3), energy, active
    count).  No body: zeros and no work done."""
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    f = np.zeros_like(x)
    e = 0.0
    n_active = 0
    for b in bodies:
        fb, eb = b.forces(x, k)
        f += fb
        e += eb
        n_active += int(np.count_nonzero(np.any(fb != 0.0, axis=1)))
    return f, e, n_active


def frictional_contact(body: ContactBody, x, k, k_t, anchor):
    """Penalty normal force plus Coulomb friction of one body (mu = body.friction > 0).

    x : (N,3) points;  k, k_t : scalar or (N,) normal and tangential penalty stiffnesses;
    anchor : (N,3) anchor points of the stick springs, NaN where a node was not in contact at the
    previous evaluation.  Nothing is modified in place (a restart must see the saved anchors).

    Returns (f (N,3) total force, E_n penalty energy, idx (m,) indices of the nodes in contact,
    f_t (m,3) their friction forces, E_t stick-spring energy 1/2 sum |f_t|^2 / k_t, new anchor
    (N,3), n_slip number of nodes slipping).  Only the nodes in contact are worked on.
    """
    x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
    N = len(x)
    k = np.ascontiguousarray(np.broadcast_to(np.asarray(k, dtype=float), (N,)))
    k_t = np.ascontiguousarray(np.broadcast_to(np.asarray(k_t, dtype=float), (N,)))
    f, ft, new = np.zeros((N, 3)), np.zeros((N, 3)), np.full((N, 3), np.nan)
    e_n, e_t, _, n_slip, _ = ck.body_forces(
        body.code,
        body.params,
        body.offset,
        body.friction,
        x,
        k,
        k_t,
        np.ascontiguousarray(anchor, dtype=float).reshape(N, 3),
        f,
        ft,
        new,
        *body.given_distances(x),
        getattr(body, "grid", None),
    )
    idx = np.flatnonzero(~np.isnan(new[:, 0]))
    return f, e_n, idx, ft[idx], e_t, new, int(n_slip)


# ---------------------------------------------------------------------- stiffness and time step
NORMAL_FD_STEP = 1e-6
"""Central-difference step of :func:`normal_gradient`, relative to max(1, |x|) [length]."""
NORMAL_FD_JUMP = 0.1
"""A change of the normal between two probes 2 eps apart beyond this is a jump, not a curvature (it
would be a radius of curvature below 20 eps, ~1e-4 cm): :func:`normal_gradient` gives 0 there."""


def normal_gradient(body: ContactBody, x) -> np.ndarray:
    """(A, 3, 3) the gradient of the outward normal, grad n = grad^2 g (symmetric), at the points x
    (A, 3), by central differences of ``signed_distance``'s normal (6 A distances; symmetrised).
    The penalty energy 1/2 k p^2 with p = offset - g has the Hessian k (n n^T - p grad n): the second
    term, which a Gauss-Newton tangent leaves out, turns the contact force as the normal turns under
    a point sliding round a curved face or a rim ((I - n n^T - t t^T) / d at distance d from a sharp
    edge of tangent t).

    Outside a convex body the normal is Lipschitz with constant 1 / g, so the differences (step eps
    = NORMAL_FD_STEP max(1, |x|)) are exact to O(eps^2 / g^3).  Where the normal jumps between the
    two probes of a direction (by more than NORMAL_FD_JUMP: the medial planes inside a box, a point
    pushed through the whole offset onto a sharp edge) 0 is returned for that point (the
    Gauss-Newton term alone) rather than a quotient of order 1 / eps."""
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    if not len(x):
        return np.zeros((0, 3, 3))
    eps = NORMAL_FD_STEP * max(1.0, float(np.abs(x).max()))
    dx = eps * np.eye(3)
    probes = np.concatenate([(x[:, None, :] + dx[None]).reshape(-1, 3), (x[:, None, :] - dx[None]).reshape(-1, 3)])
    n = np.asarray(body.signed_distance(probes)[1], dtype=float).reshape(2, len(x), 3, 3)  # (+-, A, i, comp)
    J = np.swapaxes((n[0] - n[1]) / (2.0 * eps), 1, 2)  # J[a, comp, i] = d n_comp / d x_i
    J = 0.5 * (J + np.swapaxes(J, 1, 2))
    J[np.abs(n[0] - n[1]).max(axis=(1, 2)) > NORMAL_FD_JUMP] = 0.0
    return J


def penalty_stiffness(node_mass, omega_max, factor=DEFAULT_PENALTY_FACTOR):
    """Per-node penalty stiffness k_i = factor * m_i * omega_max^2 [force/length].

    node_mass : (N,) mid-surface (U_o) masses, after mass scaling;  omega_max : the sheet's highest
    natural frequency [1/time] (2 / critical step).  See the module docstring for the reasoning.
    """
    f = _pos(factor, "contact penalty factor")
    return f * np.asarray(node_mass, dtype=float) * float(omega_max) ** 2


def contact_omega2(k, node_mass) -> float:
    """Largest k_i / m_i: the squared frequency of a node alone on its contact spring."""
    k = np.broadcast_to(np.asarray(k, dtype=float), np.shape(node_mass))
    m = np.asarray(node_mass, dtype=float)
    ok = m > 0.0
    return float(np.max(k[ok] / m[ok])) if np.any(ok) else 0.0


def contact_critical_time_step(k, node_mass) -> float:
    """Critical step 2 / sqrt(max k_i/m_i) of the contact springs alone (inf when k = 0)."""
    w2 = contact_omega2(k, node_mass)
    return math.inf if w2 <= 0.0 else 2.0 / math.sqrt(w2)


def combined_critical_time_step(omega_max, k, node_mass) -> float:
    """Bound on the critical step of sheet + contact: 2 / sqrt(omega_max^2 + max k_i/m_i)
    (Weyl: the largest eigenvalue of M^-1 (K + K_c) is at most the sum of the largest ones)."""
    return 2.0 / math.sqrt(float(omega_max) ** 2 + contact_omega2(k, node_mass))


# ---------------------------------------------------------------------- the starting configuration
def initial_penetration(bodies: Sequence[ContactBody], x, free=None, tol=None) -> list:
    """Nodes that start inside a body: for each body with any, ``(index, body, count, depth)``.

    x : (N,3) starting mid-surface positions X_o (+ U_o of a given initial state);
    free : (N,) bool, the nodes to check (default all).  Nodes whose translations are all
        prescribed cannot be pushed out, and a clamped edge on a pedestal's rim sits exactly on the
        body, so callers pass ``~fixed[:, :3].all(1)`` here;
    tol : how far inside [length] still counts as touching (default 1e-9 × the diagonal of x's
        bounding box: a sheet laid exactly on a body -- the sphere scene's lower face on the sphere
        top -- has gaps of round-off size, ~1e-16 × its coordinates).

    depth is the deepest penetration max(offset - g(x)) over the body's nodes [length].  A node
    that starts inside a body meets the full penalty force k p at once: the explicit integrator
    then sees energy appear from nowhere and stops ("creating energy"), and the static solver
    grinds through line-search cut-backs; neither says why, hence this check before any work.
    """
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    if not bodies or len(x) == 0:
        return []
    sel = np.ones(len(x), dtype=bool) if free is None else np.asarray(free, dtype=bool).reshape(len(x))
    if tol is None:
        tol = 1e-9 * float(np.linalg.norm(np.ptp(x, axis=0))) if len(x) > 1 else 0.0
    out = []
    for i, b in enumerate(bodies):
        gap, _ = b.penetration(x[sel])
        inside = gap < -tol
        n = int(np.count_nonzero(inside))
        if n:
            out.append((i, b, n, float(-gap[inside].min())))
    return out
