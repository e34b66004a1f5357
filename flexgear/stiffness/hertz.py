"""Closed forms of the contact near field: plane constants, the half-plane (Flamant) near field of
a flank patch load and 2D Hertz line contact (Weber/Johnson form).

Derivation: the theory page *Lumped model*, section *FE mesh stiffness*. SI: m, N, Pa; m/N.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..errors import ConfigError
from ..gears.material import Material

# ============================================================================================
# closed forms: plane constants, half-plane near field, Hertz line contact
# ============================================================================================
def plane_constants(material: Material, formulation: str) -> tuple[float, float]:
    """In-plane elastic constants ``(E1, nu1)`` of a 2D formulation [Pa, -].

        Plane stress (E, nu); plane strain (E/(1 - nu^2), nu/(1 - nu)), so both share one set of
        equations. ``formulation`` is "plane_stress" or "plane_strain".
    """
    E, nu = material.E, material.nu
    if formulation == "plane_stress":
        return E, nu
    if formulation == "plane_strain":
        return E / (1.0 - nu ** 2), nu / (1.0 - nu)
    raise ConfigError(f"formulation = {formulation!r}: must be 'plane_stress' or 'plane_strain'")


def contact_modulus(m1: Material, m2: Material, formulation: str = "plane_strain") -> float:
    """Contact modulus E* [Pa], 1/E* = 1/E1_1 + 1/E1_2 (plane strain: the Hertz E*)."""
    return 1.0 / (1.0 / plane_constants(m1, formulation)[0] + 1.0 / plane_constants(m2, formulation)[0])


def hertz_half_width(F: float, R: float, thickness: float, e_star: float) -> float:
    """Half-width of the 2D Hertz contact a = sqrt(4 F R / (pi L E*)) [m].

        F [N] normal force, R [m] relative radius of curvature, ``thickness`` L [m], ``e_star``
        E* [Pa].
    """
    return math.sqrt(4.0 * F * R / (math.pi * thickness * e_star))



def _panel_log_integrals(edges: np.ndarray) -> np.ndarray:
    """I_ij = int_{panel i} int_{panel j} ln|s - t| dt ds (exact), panels given by edges."""
    def G(x):
        ax = np.abs(x)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = 0.5 * x * x * np.log(ax) - 0.75 * x * x
        return np.where(ax > 0, v, 0.0)

    a, b = edges[:-1, None], edges[1:, None]
    c, d = edges[None, :-1], edges[None, 1:]
    return G(b - c) - G(a - c) - G(b - d) + G(a - d)


@lru_cache(maxsize=4096)
def log_self_energy(lo: float = -1.0, hi: float = 1.0, shape: str = "biweight", n: int = 400) -> float:
    """J = int int p^(s) p^(t) ln|s - t| ds dt of a unit-half-width patch clipped to [lo, hi].

    Parameters
    ----------
    lo, hi : float
        Support of the (clipped) patch in units of the half-width, -1 <= lo < hi <= 1.
    shape : {"biweight", "ellipse"}
        p ~ (1 - xi^2)^2 (the FE patch) or sqrt(1 - xi^2) (Hertz).
    n : int
        Number of panels (piecewise-constant density, exact panel log integrals).

    Returns
    -------
    float
        J [-] (for a half-width w add ln w). Unclipped ellipse: ln(1/2) - 1/4.
    """
    lo, hi = max(-1.0, lo), min(1.0, hi)
    if not hi > lo:
        raise ConfigError(f"patch support [{lo}, {hi}] is empty")
    edges = np.linspace(lo, hi, n + 1)
    # panel weights: exact integrals of the density over each panel
    if shape == "biweight":
        def prim(x):
            return x - 2.0 * x ** 3 / 3.0 + x ** 5 / 5.0
    elif shape == "ellipse":
        def prim(x):
            x = np.clip(x, -1.0, 1.0)
            return 0.5 * (x * np.sqrt(1.0 - x * x) + np.arcsin(x))
    else:
        raise ConfigError(f"shape = {shape!r}: must be 'biweight' or 'ellipse'")
    q = np.diff(prim(edges))
    q = q / q.sum()
    h = np.diff(edges)
    dens = q / h
    return float(dens @ _panel_log_integrals(edges) @ dens)


def halfplane_compliance(w: float, depth: float, material: Material, thickness: float,
                         formulation: str = "plane_stress", lo: float = -1.0, hi: float = 1.0,
                         shape: str = "biweight") -> float:
    """Near-field compliance of a patch load on a half-plane [m/N].

    p-weighted mean normal displacement of the loaded boundary, relative to the point at depth
    ``depth`` below the patch centre, per newton of resultant:
    ``1/(pi E1 L) [2 (ln d - J - ln w) - (1 + nu1)]``.

    Parameters
    ----------
    w : float
        Patch half-width [m].
    depth : float
        Reference depth d [m].
    material : Material
    thickness : float
        Body thickness L [m].
    formulation : {"plane_stress", "plane_strain"}
    lo, hi : float
        Clipped support in units of w (see :func:`log_self_energy`).
    shape : {"biweight", "ellipse"}
    """
    E1, nu1 = plane_constants(material, formulation)
    J = log_self_energy(float(lo), float(hi), shape) + math.log(w)
    return (2.0 * (math.log(depth) - J) - (1.0 + nu1)) / (math.pi * E1 * thickness)


def hertz_approach(F, R: float, thickness: float, m1: Material, m2: Material, depth1: float,
                   depth2: float, formulation: str = "plane_strain"):
    """Approach of two bodies in 2D Hertz line contact, between points at depths d1, d2 [m].

    ``delta = sum_i P/(pi E1_i) [2 ln(2 d_i / a) - 1/2 - nu1_i] + P/(2 pi E*)`` with P = F/L and
    a the Hertz half-width; consistent with :func:`halfplane_compliance` (weighted-mean
    displacements) and with Johnson's centre-line result.

    Parameters
    ----------
    F : float or ndarray
        Normal force [N] (>= 0).
    R : float
        Relative radius of curvature [m].
    thickness : float
        Contact length L [m].
    m1, m2 : Material
    depth1, depth2 : float
        Reference depths [m].
    formulation : {"plane_strain", "plane_stress"}
    """
    F = np.asarray(F, dtype=float)
    E1a, nua = plane_constants(m1, formulation)
    E1b, nub = plane_constants(m2, formulation)
    es = 1.0 / (1.0 / E1a + 1.0 / E1b)
    P = F / thickness
    out = np.zeros_like(P)
    pos = P > 0
    a = np.sqrt(4.0 * P[pos] * R / (math.pi * es))
    out[pos] = (P[pos] / (math.pi * E1a) * (2.0 * np.log(2.0 * depth1 / a) - 0.5 - nua)
                + P[pos] / (math.pi * E1b) * (2.0 * np.log(2.0 * depth2 / a) - 0.5 - nub)
                + P[pos] / (2.0 * math.pi * es))
    return out if out.ndim else float(out)


