"""Linear elastic isotropic material (SI units)."""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import ConfigError


@dataclass(frozen=True)
class Material:
    """Isotropic linear elastic material.

    Parameters
    ----------
    E : float
        Young's modulus [Pa]. Paper default (steel): 2.1e11.
    nu : float
        Poisson's ratio [-]. Paper default: 0.3.
    rho : float
        Density [kg/m^3]. Not in the paper; default 7850 (steel).
    """

    E: float = 2.1e11
    nu: float = 0.3
    rho: float = 7850.0

    def __post_init__(self):
        if not self.E > 0:
            raise ConfigError(f"material.E = {self.E!r}: Young's modulus must be > 0 Pa")
        if not (-1.0 < self.nu < 0.5):
            raise ConfigError(f"material.nu = {self.nu!r}: Poisson's ratio must lie in (-1, 0.5)")
        if not self.rho > 0:
            raise ConfigError(f"material.rho = {self.rho!r}: density must be > 0 kg/m^3")

    @property
    def G(self) -> float:
        """Shear modulus [Pa]."""
        return self.E / (2.0 * (1.0 + self.nu))


def effective_modulus(m1: Material, m2: Material) -> float:
    """Hertz contact modulus E* [Pa], 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2 (paper Eq. 5).

    For two steels with E = 2.1e11 Pa, nu = 0.3 this gives 1.1538e11 Pa.
    """
    return 1.0 / ((1.0 - m1.nu**2) / m1.E + (1.0 - m2.nu**2) / m2.E)
