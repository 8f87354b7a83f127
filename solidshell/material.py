"""Shell sections: the rigidities that enter the strain energy of Eq. (7).

Every section exposes, in a consistent unit system (the paper's gf-cm-s for fabrics):

``C_m`` (3,3)  membrane rigidity [force/length] acting on (eps_xx, eps_yy, gamma_xy)
``C_b`` (3,3)  bending rigidity [force*length] acting on the bending strains (1/length)
``C_t`` (2,2)  transverse shear rigidity [force/length] acting on (gamma_zx, gamma_zy)
``E_z``        thickness modulus [force/length] acting on eps_zz (a resultant, like C_m)
``thickness``  h [length];  ``mass_per_area`` mu [mass/area];  ``weight_per_area`` [force/area]
``warp_angle`` angle [rad] of the material x axis (the warp) from global X, about global Z.

The local frame is the one of Eq. (6): z along the mid-surface normal, x along the warp projected
on the tangent plane, y = z cross x.  Because of the plane-stress enforcement and the uncoupled
energy of Eq. (7), all four rigidities are resultants (integrated through the thickness).
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields

import numpy as np

from .errors import InputError
from .units import G0


def _positive(name: str, value: float, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number [{unit}], got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise InputError(f"{name} must be positive and finite [{unit}], got {value!r}")
    return v


@dataclass(frozen=True)
class Fabric:
    """A woven fabric described by its resultant rigidities (Table 1 of the paper, KES-style data).

    Parameters (gf-cm-s units)
    --------------------------
    tensile_warp, tensile_weft : float
        Tensile rigidities [gf/cm] along warp (material x) and weft (material y).
    shear : float
        In-plane shear rigidity [gf/cm].
    bending_warp, bending_weft, torsion : float
        Bending rigidities [gf*cm^2/cm] for curvature along warp, along weft, and the torsional
        rigidity acting on the engineering twist gamma_b,xy (so that M_xy = torsion * gamma_b,xy,
        the role D(1-nu)/2 plays for an isotropic plate).
    weight : float
        Weight per area [gf/cm^2]; the mass per area is weight / g0.
    thickness : float
        Thickness h [cm]; it spans the director (h * X_n) and sets the director masses mu h^2/4.
    warp_angle : float
        Angle of the warp from global X about global Z [degrees].
    poisson : float
        In-plane Poisson coupling nu (default 0).  C_m[0,1] = nu*sqrt(T_warp*T_weft) and likewise
        for C_b.  Fabric data sets (KES) give no coupling and drape codes commonly take 0; with 0 the
        section is positive definite for any positive rigidities.
    transverse_shear : float or None
        Transverse shear rigidity C_t (isotropic, [gf/cm]).  The paper does not state it.  Default:
        5/6 * T_mean / 2 with T_mean the mean tensile rigidity -- the shear correction factor times
        the shear modulus of an equivalent isotropic, nu = 0 sheet of the same tensile rigidity.  The
        transverse-shear share of a bending deflection over a length l is ~ B / (C_t l^2); with this
        default it is < 1e-3 for any l >= 0.5 cm of wool, i.e. the sheet behaves as Kirchhoff-thin,
        while C_t stays comparable to E_z so that it does not lower the explicit critical time step.
    thickness_modulus : float or None
        E_z of Eq. (7) [gf/cm].  The paper does not state it.  Default: T_mean (an equivalent
        isotropic sheet's E*h).  It only controls how much the director stretches, which the drape
        does not feel as long as E_z >> bending rigidity / h^2; it sets the explicit critical step
        h*sqrt(mu/E_z) (DESIGN.md), so making it stiffer than needed costs run time.
    """

    tensile_warp: float
    tensile_weft: float
    shear: float
    bending_warp: float
    bending_weft: float
    torsion: float
    weight: float
    thickness: float
    warp_angle: float = 0.0
    poisson: float = 0.0
    transverse_shear: float | None = None
    thickness_modulus: float | None = None
    name: str = field(default="fabric", compare=False)

    def __post_init__(self):
        for n, u in (
            ("tensile_warp", "gf/cm"),
            ("tensile_weft", "gf/cm"),
            ("shear", "gf/cm"),
            ("bending_warp", "gf*cm^2/cm"),
            ("bending_weft", "gf*cm^2/cm"),
            ("torsion", "gf*cm^2/cm"),
            ("weight", "gf/cm^2"),
            ("thickness", "cm"),
        ):
            object.__setattr__(self, n, _positive(n, getattr(self, n), u))
        for n in ("transverse_shear", "thickness_modulus"):
            if getattr(self, n) is not None:
                object.__setattr__(self, n, _positive(n, getattr(self, n), "gf/cm"))
        try:
            nu = float(self.poisson)
        except (TypeError, ValueError):
            raise InputError(f"poisson must be a number, got {self.poisson!r}") from None
        if not (0.0 <= nu < 1.0):
            raise InputError(f"poisson must lie in [0, 1), got {self.poisson!r}")
        object.__setattr__(self, "poisson", nu)
        try:
            object.__setattr__(self, "warp_angle", float(self.warp_angle))
        except (TypeError, ValueError):
            raise InputError(f"warp_angle must be a number [deg], got {self.warp_angle!r}") from None

    @classmethod
    def wool(cls, **overrides) -> "Fabric":
        """The wool fabric of Table 1 (Kang & Yu [10]), gf-cm-s units; keywords override fields.
        Its numbers live in the fabric library (solidshell/fabrics.toml, entry "wool")."""
        from .fabrics import fabric  # the library builds Fabrics: imported here, not at the top

        return fabric("wool", **overrides)

    @property
    def tensile_mean(self) -> float:
        return 0.5 * (self.tensile_warp + self.tensile_weft)

    @property
    def C_m(self) -> np.ndarray:
        c = self.poisson * math.sqrt(self.tensile_warp * self.tensile_weft)
        return np.array([[self.tensile_warp, c, 0.0], [c, self.tensile_weft, 0.0], [0.0, 0.0, self.shear]])

    @property
    def C_b(self) -> np.ndarray:
        c = self.poisson * math.sqrt(self.bending_warp * self.bending_weft)
        return np.array([[self.bending_warp, c, 0.0], [c, self.bending_weft, 0.0], [0.0, 0.0, self.torsion]])

    @property
    def C_t(self) -> np.ndarray:
        ct = self.transverse_shear if self.transverse_shear is not None else 5.0 / 6.0 * self.tensile_mean / 2.0
        return ct * np.eye(2)

    @property
    def E_z(self) -> float:
        return self.thickness_modulus if self.thickness_modulus is not None else self.tensile_mean

    @property
    def weight_per_area(self) -> float:
        return self.weight

    @property
    def mass_per_area(self) -> float:
        """Mass per area [gf*s^2/cm^3] = weight / g0."""
        return self.weight / G0

    @property
    def warp_angle_rad(self) -> float:
        return math.radians(self.warp_angle)


FABRIC_FIELDS = tuple(f.name for f in fields(Fabric) if f.name != "name")
"""The Fabric fields a scene's ``[material]`` table may set beside ``fabric`` and ``name``."""


@dataclass(frozen=True)
class IsotropicShell:
    """Homogeneous isotropic linear-elastic shell (any consistent units).

    Parameters
    ----------
    E : Young's modulus [force/length^2];  nu : Poisson's ratio;  h : thickness [length];
    density : mass per volume [mass/length^3] (default 0: massless, statics only);
    shear_factor : transverse shear correction factor kappa (default 5/6).

    Plane-stress enforcement (Section 2) gives C_m = E h/(1-nu^2) [[1,nu,0],[nu,1,0],[0,0,(1-nu)/2]],
    C_b = h^2/12 C_m, C_t = kappa G h I, and E_z = E h for the thickness strain, which is uncoupled
    from the in-plane strains (this is what removes thickness locking).
    """

    E: float
    nu: float
    h: float
    density: float = 0.0
    shear_factor: float = 5.0 / 6.0
    gravity: float = G0
    name: str = field(default="isotropic", compare=False)

    def __post_init__(self):
        object.__setattr__(self, "E", _positive("E", self.E, "force/length^2"))
        object.__setattr__(self, "h", _positive("h", self.h, "length"))
        object.__setattr__(self, "shear_factor", _positive("shear_factor", self.shear_factor, "-"))
        nu = float(self.nu)
        if not (-1.0 < nu < 0.5):
            raise InputError(f"nu must lie in (-1, 0.5), got {self.nu!r}")
        object.__setattr__(self, "nu", nu)
        rho = float(self.density)
        if not math.isfinite(rho) or rho < 0.0:
            raise InputError(f"density must be >= 0 [mass/length^3], got {self.density!r}")
        object.__setattr__(self, "density", rho)

    thickness = property(lambda self: self.h)
    warp_angle_rad = property(lambda self: 0.0)

    @property
    def C_m(self) -> np.ndarray:
        D = self.E * self.h / (1.0 - self.nu**2)
        return D * np.array([[1.0, self.nu, 0.0], [self.nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - self.nu)]])

    @property
    def C_b(self) -> np.ndarray:
        return self.h**2 / 12.0 * self.C_m

    @property
    def C_t(self) -> np.ndarray:
        G = self.E / (2.0 * (1.0 + self.nu))
        return self.shear_factor * G * self.h * np.eye(2)

    @property
    def E_z(self) -> float:
        return self.E * self.h

    @property
    def mass_per_area(self) -> float:
        return self.density * self.h

    @property
    def weight_per_area(self) -> float:
        """Weight per area = mass per area * gravity (gravity defaults to g0 in cm/s^2)."""
        return self.mass_per_area * self.gravity


ISOTROPIC_FIELDS = tuple(f.name for f in fields(IsotropicShell) if f.name not in ("gravity", "name"))
"""The IsotropicShell fields a scene's ``material.isotropic`` table may set (gravity is the unit system's)."""
ISOTROPIC_REQUIRED = tuple(f.name for f in fields(IsotropicShell) if f.default is MISSING)
"""Those it must set (E, nu, h)."""
