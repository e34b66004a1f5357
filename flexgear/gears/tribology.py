"""Per-contact tribology of a lubricated tooth pair as compiled kernels: friction coefficient, EHL film thickness of a line contact, squeeze-film damping.

SI in, SI out (each formula's original units converted here, once). A contact is described by
its sliding and entrainment speeds v_s = u_2 - u_1, u_e = (u_1 + u_2) / 2 [m/s]
(:func:`flexgear.gears.lubrication.surface_speeds`), load per face width w [N/m], relative
radius of curvature R [m] and Hertz modulus E* [Pa]; a mesh's parameters come in one
:class:`FrictionParameters` row (:func:`friction_parameters`).

* :func:`friction_coefficient`, signed like v_s:
  ``mu = mu_model(max(|v_s|, v_0), max(|u_e|, v_0), w, R) tanh(v_s / v_0)``; the tanh gives
  Newton a tangent through the reversal at the pitch point, the floors keep the Benedict &
  Kelley logarithm finite there (:func:`friction_coefficient_slopes`: the same coefficient with its
  derivatives, the factors that no contact variable changes taken once, :func:`law_constants`).
  mu_model: constant (Coulomb), Benedict & Kelley (1961, ASLE Trans. 4, 59-70; 0 where the
  logarithm turns negative) or Xu, Kahraman, Anderson & Maddock (2007, ASME J. Mech. Des. 129,
  58-68).
* Film thickness (Dowson & Higginson 1977; central: Dowson & Toyoda 1979), U = eta_0 u_e /
  (E' R), G = alpha E', W = w / (E' R), E' = 2 E*: h_c = 3.06 R U^0.69 G^0.56 W^-0.10,
  h_min = 2.65 R U^0.70 G^0.54 W^-0.13.
* Squeeze film of a cylinder approaching a plane (Reynolds, rigid surfaces, isoviscous):
  c = 3 sqrt(2) pi eta_0 L (R / h)^(3/2) [N s/m]; in a mesh evaluated at h = h_c
  (:func:`squeeze_film_slopes`).

Formulas in their original units, sources and ranges: the guide page *Lubrication*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..kernels import kernel

#: Friction coefficient models and their codes in :class:`FrictionParameters`.
#: The friction-coefficient models of ``[lubrication] friction_model``.
FRICTION_MODELS = ("constant", "benedict_kelley", "xu")
CONSTANT, BENEDICT_KELLEY, XU = 0, 1, 2
MODEL_CODES = dict(zip(FRICTION_MODELS, (CONSTANT, BENEDICT_KELLEY, XU)))

#: b_1 ... b_9 of Xu, Kahraman, Anderson & Maddock (2007), ASME J. Mech. Des. 129, 58-68, regressed on
#: their thermal EHL predictions for a 75W90 gear oil (units: :func:`xu_coefficient`).
#: b1 ... b9 of Xu, Kahraman, Anderson & Maddock (2007).
XU_2007 = (-8.916465, 1.03303, 1.036077, -0.354068, 2.812084, -0.100601, 0.752755, -0.390958, 0.620305)
# Benedict & Kelley's constant in their units (lb/in, cP, in/s) and its SI value for w [N/m],
# eta_0 [Pa s] and speeds [m/s]: 3.17e8 in^4 (1e-3 Pa s / cP) / lbf
LBF = 4.4482216152605  # N
INCH = 0.0254  # m
BK_CONSTANT_US = 3.17e8
BK_CONSTANT_SI = BK_CONSTANT_US * INCH**4 * 1e-3 / LBF
BK_SLOPE = 0.0127
# Dowson & Higginson (minimum) and Dowson & Toyoda (central) line-contact film thickness
HMIN_C, HMIN_U, HMIN_G, HMIN_W = 2.65, 0.70, 0.54, -0.13
HC_C, HC_U, HC_G, HC_W = 3.06, 0.69, 0.56, -0.10
SQUEEZE_C = 3.0 * math.sqrt(2.0) * math.pi


class FrictionParameters(NamedTuple):
    """Friction and lubrication of the meshes (one row per mesh) as the kernels take them."""

    model: np.ndarray  # (M,) int: CONSTANT, BENEDICT_KELLEY or XU
    mu: np.ndarray  # (M,) float: Coulomb coefficient [-] (constant model)
    v0: np.ndarray  # (M,) float: regularisation speed v_0 [m/s]
    eta: np.ndarray  # (M,) float: dynamic viscosity eta_0 [Pa s] (nan: no lubricant)
    alpha: np.ndarray  # (M,) float: pressure-viscosity coefficient [1/Pa] (nan: no lubricant)
    e_star: np.ndarray  # (M,) float: Hertz modulus E* of the pair [Pa]
    roughness: np.ndarray  # (M,) float: composite RMS roughness [m] (nan: not given)
    xu: np.ndarray  # (M, 9) float: b_1 ... b_9 of the xu model


def friction_parameters(lubrication, meshes, e_star: float) -> FrictionParameters:
    """The :class:`FrictionParameters` of ``meshes`` = [(gear a name, gear b name), ...] under
    ``lubrication`` (a :class:`flexgear.gears.lubrication.Lubrication`), all of Hertz modulus
    ``e_star`` [Pa]."""
    m = len(meshes)
    lub = lubrication.lubricant
    rough = [lubrication.mesh_roughness(a, b) for a, b in meshes]
    xu = lubrication.xu_coefficients if lubrication.xu_coefficients is not None else XU_2007
    return FrictionParameters(
        model=np.full(m, MODEL_CODES[lubrication.friction_model], np.int64),
        mu=np.full(m, lubrication.friction_coefficient if lubrication.friction_coefficient is not None else np.nan),
        v0=np.full(m, float(lubrication.sliding_speed_scale)),
        eta=np.full(m, lub.viscosity if lub is not None else np.nan),
        alpha=np.full(m, lub.pressure_viscosity if lub is not None else np.nan),
        e_star=np.full(m, float(e_star)),
        roughness=np.array([np.nan if r is None else r for r in rough], float),
        xu=np.tile(np.asarray(xu, float), (m, 1)))


@kernel(error_model="numpy")
def hertz_pressure(w, R, e_star):
    """Maximum Hertz pressure [Pa] of a line contact: sqrt(w E* / (pi R))."""
    return math.sqrt(w * e_star / (math.pi * R))


@kernel(error_model="numpy")
def benedict_kelley_coefficient(v_s, v_sum, w, eta):
    """Benedict & Kelley's coefficient [-] at sliding speed ``v_s`` > 0 and sum velocity
    ``v_sum`` = u_1 + u_2 > 0 [m/s], load per face width ``w`` [N/m], viscosity ``eta`` [Pa s];
    0 where the formula turns negative."""
    arg = BK_CONSTANT_SI * w / (eta * v_s * v_sum * v_sum)
    if arg <= 1.0:
        return 0.0
    return BK_SLOPE * math.log10(arg)


@kernel(error_model="numpy")
def xu_coefficient(sr, p_h, u_e, eta, R, roughness, b):
    """Xu et al.'s coefficient [-] at slide-to-roll ratio ``sr`` = v_s / u_e [-], Hertz
    pressure ``p_h`` [Pa], entrainment speed ``u_e`` [m/s], viscosity ``eta`` [Pa s], relative
    radius ``R`` [m], RMS roughness ``roughness`` [m]; ``b`` = b_1 ... b_9. Evaluated in the
    formula's units: P_h GPa, nu_0 cP, V_e m/s, R m, S um."""
    ph = p_h * 1e-9
    nu0 = eta * 1e3
    s = roughness * 1e6
    x = abs(sr) * ph * math.log10(nu0)
    f = b[0] + b[3] * x + b[4] * math.exp(-x) + b[8] * math.exp(s)
    return math.exp(f) * ph ** b[1] * abs(sr) ** b[2] * u_e ** b[5] * nu0 ** b[6] * R ** b[7]


@kernel(error_model="numpy")
def friction_coefficient(table, m, v_s, u_e, w, R):
    """Friction coefficient [-] of a contact of mesh ``m`` (row of ``table``, a
    :class:`FrictionParameters`), signed like ``v_s`` (module docstring): sliding speed
    ``v_s`` and entrainment speed ``u_e`` [m/s], load per face width ``w`` [N/m], relative
    radius ``R`` [m]."""
    v0 = table.v0[m]
    sign = math.tanh(v_s / v0)
    model = table.model[m]
    if model == CONSTANT:
        return table.mu[m] * sign
    vs = max(abs(v_s), v0)
    ue = max(abs(u_e), v0)
    if model == BENEDICT_KELLEY:
        return benedict_kelley_coefficient(vs, 2.0 * ue, w, table.eta[m]) * sign
    ph = hertz_pressure(w, R, table.e_star[m])
    return xu_coefficient(vs / ue, ph, ue, table.eta[m], R, table.roughness[m], table.xu[m]) * sign


#: |v_s| / v_0 from which tanh(v_s / v_0) is +-1 in double precision (1 - tanh(20) = 8.5e-18 is
#: below half the spacing of the doubles under 1): :func:`coefficient_slopes_at` skips the tanh there.
TANH_ONE = 20.0


def law_constants(table: FrictionParameters) -> np.ndarray:
    """(M, 2): the part of each mesh's friction coefficient that no contact variable changes, for
    :func:`contact_constants` (Xu et al.: b_1 + b_9 e^S + b_7 ln nu_0 + b_2 ln(1e-9 sqrt(E*/pi))
    and 1e-9 sqrt(E*/pi) log10(nu_0) in the formula's units; 0 for the other models)."""
    out = np.zeros((len(table.model), 2))
    for m in range(len(table.model)):
        if table.model[m] == XU:
            b = table.xu[m]
            nu0 = table.eta[m] * 1e3  # cP
            p = 1e-9 * math.sqrt(table.e_star[m] / math.pi)  # p_h [GPa] sqrt(R / w)
            out[m] = (b[0] + b[8] * math.exp(table.roughness[m] * 1e6) + b[6] * math.log(nu0) + b[1] * math.log(p),
                      p * math.log10(nu0))
    return out


@kernel(error_model="numpy", inline="always")
def contact_constants(table, m, law, u_e, R):
    """(c_0, c_1): the part of mesh ``m``'s friction coefficient (row of ``table``, a
    :class:`FrictionParameters`; ``law`` its row of :func:`law_constants`) that a contact's
    entrainment speed ``u_e`` [m/s] and relative radius ``R`` [m] fix, for
    :func:`coefficient_slopes_at` (a solver whose u_e and R are known ahead of the sliding
    speed and the load takes their logarithms and powers once).

    Constant: (mu, 0). Benedict & Kelley: c_0 = ln(K / (eta (2 u_e)^2)), mu = 0.0127 log10 of
    c_0 + ln w - ln v_s. Xu et al.: ln mu = c_0 + b_2/2 ln w + b_3 ln v_s + b_4 x + b_5 e^-x,
    x = c_1 v_s sqrt(w) (:func:`xu_coefficient` with its factors gathered; b_k as there
    numbered from 1). u_e is floored at v_0 as in :func:`friction_coefficient`."""
    model = table.model[m]
    if model == CONSTANT:
        return table.mu[m], 0.0
    ue = max(abs(u_e), table.v0[m])
    if model == BENEDICT_KELLEY:
        return math.log(BK_CONSTANT_SI / (table.eta[m] * 4.0 * ue * ue)), 0.0
    b = table.xu[m]
    c0 = law[0] + (b[5] - b[2]) * math.log(ue) + (b[7] - 0.5 * b[1]) * math.log(R)
    return c0, law[1] / (math.sqrt(R) * ue)


@kernel(error_model="numpy", inline="always")
def coefficient_slopes_at(table, m, c0, c1, v_s, w, ln_w, sqrt_w):
    """(mu, dmu/dv_s, dmu/dw, dmu/d ln u_e) [-, s/m, m/N, -] of :func:`friction_coefficient` at
    sliding speed ``v_s`` [m/s] and load per face width ``w`` [N/m] > 0 (``ln_w``, ``sqrt_w``:
    its logarithm and square root, shared by a mesh's contacts; unused by the constant model) of
    a contact of mesh ``m`` whose entrainment speed and relative radius gave (``c0``, ``c1``)
    (:func:`contact_constants`; the last slope ignores u_e's floor at v_0,
    :func:`friction_coefficient_slopes` applies it): one logarithm and two exponentials (Xu et
    al.) instead of about fifteen transcendental calls, and no tanh where it is +-1
    (:data:`TANH_ONE`)."""
    v0 = table.v0[m]
    if v_s >= TANH_ONE * v0:  # (no division where the tanh is +-1: called for every pair, every step)
        th, dsign = 1.0, 0.0
    elif v_s <= -TANH_ONE * v0:
        th, dsign = -1.0, 0.0
    else:
        th = math.tanh(v_s / v0)
        dsign = (1.0 - th * th) / v0
    model = table.model[m]
    if model == CONSTANT:
        return c0 * th, c0 * dsign, 0.0, 0.0
    a_vs = abs(v_s)
    vs = max(a_vs, v0)
    dvs = (1.0 if v_s >= 0.0 else -1.0) if a_vs > v0 else 0.0  # d vs / d v_s
    lvs = math.log(vs)
    if model == BENEDICT_KELLEY:
        la = c0 + ln_w - lvs  # ln of Benedict & Kelley's argument
        if la <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        k = BK_SLOPE / math.log(10.0)
        mu = k * la
        return mu * th, mu * dsign - k / vs * dvs * th, k / w * th, -2.0 * k * th
    b = table.xu[m]
    x = c1 * vs * sqrt_w
    ex = math.exp(-x)
    mu = math.exp(c0 + 0.5 * b[1] * ln_w + b[2] * lvs + b[3] * x + b[4] * ex)
    gx = (b[3] - b[4] * ex) * x  # x d f / d x
    return (mu * th, mu * (dsign + (gx + b[2]) / vs * dvs * th), mu * (gx + b[1]) / (2.0 * w) * th,
            mu * (b[5] - b[2] - gx) * th)  # c_0 holds (b_6 - b_3) ln u_e, x falls as 1 / u_e


@kernel(error_model="numpy", inline="always")
def friction_coefficient_slopes(table, law, m, v_s, u_e, w, R):
    """(mu, dmu/dv_s, dmu/du_e, dmu/dw) [-, s/m, s/m, m/N] of :func:`friction_coefficient` at
    load per face width ``w`` > 0 [N/m]: the coefficient and its exact partial derivatives, for
    the Newton tangent of the friction force mu(v_s, u_e, w) w L (the floors at v_0 make the
    model's slopes zero below v_0), through :func:`contact_constants` and
    :func:`coefficient_slopes_at` (``law``: mesh ``m``'s row of :func:`law_constants`): about
    six transcendental calls instead of the formula's fifteen."""
    c0, c1 = contact_constants(table, m, law, u_e, R)
    if table.model[m] == CONSTANT:
        ln_w, sqrt_w = 0.0, 0.0
    else:
        ln_w, sqrt_w = math.log(w), math.sqrt(w)
    mu, dmu_v, dmu_w, dmu_l = coefficient_slopes_at(table, m, c0, c1, v_s, w, ln_w, sqrt_w)
    a_ue = abs(u_e)
    dmu_u = (dmu_l / a_ue if u_e >= 0.0 else -dmu_l / a_ue) if a_ue > table.v0[m] else 0.0
    return mu, dmu_v, dmu_u, dmu_w


@kernel(error_model="numpy")
def central_film_thickness(u_e, eta, alpha, w, R, e_star):
    """Central film thickness h_c [m] of an EHL line contact (Dowson & Toyoda 1979): entrainment
    speed ``u_e`` [m/s], ``eta`` [Pa s], ``alpha`` [1/Pa], load per face width ``w`` [N/m]
    (> 0), relative radius ``R`` [m], Hertz modulus ``e_star`` [Pa]. 0 without entrainment."""
    if u_e == 0.0:
        return 0.0
    ep = 2.0 * e_star
    return HC_C * R * (eta * abs(u_e) / (ep * R)) ** HC_U * (alpha * ep) ** HC_G * (w / (ep * R)) ** HC_W


@kernel(error_model="numpy")
def minimum_film_thickness(u_e, eta, alpha, w, R, e_star):
    """Minimum film thickness h_min [m] of an EHL line contact (Dowson & Higginson 1977);
    arguments as :func:`central_film_thickness`."""
    if u_e == 0.0:
        return 0.0
    ep = 2.0 * e_star
    return HMIN_C * R * (eta * abs(u_e) / (ep * R)) ** HMIN_U * (alpha * ep) ** HMIN_G * (w / (ep * R)) ** HMIN_W


@kernel(error_model="numpy")
def squeeze_film_damping(eta, R, h, length):
    """Damping coefficient [N s/m] of the film between two cylinders of relative radius ``R``
    [m] and length ``length`` [m] approaching each other at film thickness ``h`` [m] through an
    isoviscous Newtonian film of viscosity ``eta`` [Pa s] (rigid surfaces, fully flooded):
    F = c dh/dt, c = 3 sqrt(2) pi eta L (R / h)^(3/2)."""
    return SQUEEZE_C * eta * length * (R / h) ** 1.5


def squeeze_film_factor(eta, alpha, e_star, length) -> float:
    """K [N s/m] of a mesh's squeeze-film coefficient written out in the contact's variables,
    c = K (u_e / R)^(-3/2 0.69) (w / R)^(3/2 0.10): :func:`squeeze_film_damping` at
    :func:`central_film_thickness`, whose R, U, G and W combine so (``eta`` [Pa s], ``alpha``
    [1/Pa], ``e_star`` [Pa], ``length`` [m]; :func:`squeeze_film_slopes`)."""
    ep = 2.0 * e_star
    return (SQUEEZE_C * eta * length * HC_C ** -1.5 * (eta / ep) ** (-1.5 * HC_U) * (alpha * ep) ** (-1.5 * HC_G)
            * ep ** (1.5 * HC_W))


@kernel(error_model="numpy", fastmath=False)
def squeeze_film_slopes(factor, v0, u_e, w, R):
    """(c, dc/du_e, dc/dw) [N s/m, N s^2/m^2, s]: the squeeze-film damping coefficient of a
    contact at the central film thickness h_c(max(|u_e|, v0), w, R), c = 3 sqrt(2) pi eta L
    (R / h_c)^(3/2), and its exact partial derivatives for the Newton tangent, from the mesh's
    ``factor`` (:func:`squeeze_film_factor`; one exponential and two logarithms instead of the
    four powers of the kernels composed): entrainment speed ``u_e`` [m/s], load per face width
    ``w`` [N/m], relative radius ``R`` [m]; 0 for w <= 0 (no film pressure without load)."""
    if w <= 0.0:
        return 0.0, 0.0, 0.0
    ue = max(abs(u_e), v0)
    c = factor * math.exp(-1.5 * HC_U * math.log(ue / R) - 1.5 * HC_W * math.log(w / R))
    due = 0.0
    if abs(u_e) > v0:
        due = -1.5 * HC_U * c / ue * (1.0 if u_e >= 0.0 else -1.0)
    return c, due, -1.5 * HC_W * c / w


@dataclass(frozen=True)
class FrictionLaw:
    """The friction coefficient of one mesh as a vectorised Python function (for quasi-static
    integrals such as :func:`flexgear.gears.lubrication.path_losses`)."""

    table: FrictionParameters

    def coefficient(self, v_s, u_e, w, R):
        """mu [-] at arrays of v_s, u_e [m/s], w [N/m], R [m] (:func:`friction_coefficient`)."""
        v_s, u_e, w, R = np.broadcast_arrays(*(np.asarray(a, float) for a in (v_s, u_e, w, R)))
        out = np.empty(v_s.shape)
        flat = out.reshape(-1)
        for i, args in enumerate(zip(v_s.ravel(), u_e.ravel(), w.ravel(), R.ravel())):
            flat[i] = friction_coefficient(self.table, 0, *args)
        return out


def friction_law(lubrication, gear_a: str, gear_b: str, e_star: float) -> FrictionLaw:
    """:class:`FrictionLaw` of the mesh between the gears named ``gear_a`` and ``gear_b``."""
    return FrictionLaw(friction_parameters(lubrication, [(gear_a, gear_b)], e_star))
