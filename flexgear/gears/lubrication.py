"""Tooth friction and lubrication of involute spur gears: the lubricant, the kinematics of a contact point, and the friction loss of a mesh over its path of contact. All SI.

* :class:`Lubricant`: viscosity eta_0 [Pa s], pressure-viscosity coefficient alpha [1/Pa] and
  density [kg/m^3], given directly or from an ISO VG grade (:data:`ISO_VG`) and the oil
  temperature by the ASTM D341 (Walther) relation (:func:`walther_viscosity`).
* :func:`surface_speeds`, :func:`pair_speeds`: at s on the line of action (from the pitch point,
  positive towards gear 1's tip) the roll angles are xi_1 = (r_b1 tan a_w + s) / r_b1 and
  xi_2 = (r_b2 tan a_w -+ s) / r_b2 (- external, + internal); the surfaces move at
  u_i = omega_i r_bi xi_i, so the sliding speed v_s = u_2 - u_1 = -omega_1 s (1 +- z_1 / z_2)
  (flexgear's sign in every model and in the results) changes sign at the pitch point.
* :func:`loss_factor` (H_V of Niemann & Winter / Ohlendorf, ISO/TR 14179-2) and
  :func:`path_losses` (friction power along the path for any coefficient and load sharing).
* :func:`nominal_lubrication`: a mesh at its static load before any run (``flexgear info``):
  H_V, the efficiency with equal load sharing and the pitch point's EHL film.

The per-contact formulas the solver evaluates are in :mod:`flexgear.gears.tribology`; formulas
and sources: the guide page *Lubrication*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, GeometryError
from .tribology import (FRICTION_MODELS, XU_2007,  # noqa: F401  (the first two re-exported: the config layer reads them here)
                        central_film_thickness, minimum_film_thickness)

# ============================================================================================
# lubricant: ISO VG grades and ASTM D341
# ============================================================================================
#: Viscosity index of the ISO VG grades' 100 degC viscosities [-]: the reference mineral oil of
#: viscosity classification charts.
ISO_VG_VISCOSITY_INDEX = 95
#: ISO VG grade -> (kinematic viscosity at 40 degC, at 100 degC) [m^2/s]. 40 degC: the ISO 3448
#: mid-point of the grade; 100 degC: the viscosity that gives the grade's mid-point a viscosity
#: index of 95 by ASTM D2270 (Table 1 with linear interpolation; above 70 mm^2/s its equations
#: for L and H), solved to four significant digits. Grades below VG 7 have no 100 degC
#: viscosity of VI 95 (D2270 defines the index from 2 mm^2/s at 100 degC).
ISO_VG = {
    7: (6.8e-6, 2.064e-6),
    10: (10.0e-6, 2.637e-6),
    15: (15.0e-6, 3.381e-6),
    22: (22.0e-6, 4.254e-6),
    32: (32.0e-6, 5.290e-6),
    46: (46.0e-6, 6.645e-6),
    68: (68.0e-6, 8.530e-6),
    100: (100.0e-6, 11.07e-6),
    150: (150.0e-6, 14.55e-6),
    220: (220.0e-6, 18.75e-6),
    320: (320.0e-6, 23.96e-6),
    460: (460.0e-6, 30.35e-6),
    680: (680.0e-6, 39.06e-6),
    1000: (1000.0e-6, 49.86e-6),
    1500: (1500.0e-6, 64.22e-6),
    2200: (2200.0e-6, 81.18e-6),
    3200: (3200.0e-6, 101.6e-6),
}
#: Oil temperatures [degC] flexgear accepts for an ISO VG grade. ASTM D341 holds for homogeneous
#: liquids, between the cloud point and the initial boiling point (its Sec. 3): mineral gear oils
#: reach their pour points at -10 to -30 degC; above 150 degC they oxidise quickly, and the
#: extrapolation from 40 and 100 degC loses its basis.
OIL_TEMPERATURE_RANGE_C = (-20.0, 150.0)
#: why, for the messages that refuse a temperature outside it
OIL_TEMPERATURE_REASON = ("D341 holds between an oil's cloud point and boiling point; mineral gear oils reach their "
                          "pour points at -10 to -30 degC and oxidise quickly above 150 degC")
#: Kinematic viscosities [m^2/s] within which ASTM D341's equations hold (its Sec. 5: Z with the
#: exponential corrections, 0.21 to 2e7 mm^2/s).
D341_VISCOSITY_RANGE = (0.21e-6, 2.0e7 * 1e-6)
KELVIN = 273.15


def d341_z(nu):
    """ASTM D341 variable Z of a kinematic viscosity ``nu`` [m^2/s] (computed in mm^2/s):
    Z = nu + 0.7 + exp(-1.47 - 1.84 nu - 0.51 nu^2)."""
    v = np.asarray(nu, float) * 1e6
    return v + 0.7 + np.exp(-1.47 - 1.84 * v - 0.51 * v * v)


def d341_nu(z):
    """Inverse of :func:`d341_z` as ASTM D341 gives it: nu = (Z - 0.7) - exp(-0.7487
    - 3.295 (Z - 0.7) + 0.6119 (Z - 0.7)^2 - 0.3193 (Z - 0.7)^3) [mm^2/s], returned in m^2/s."""
    w = np.asarray(z, float) - 0.7
    return (w - np.exp(-0.7487 - 3.295 * w + 0.6119 * w * w - 0.3193 * w ** 3)) * 1e-6


def walther_constants(t1: float, nu1: float, t2: float, nu2: float) -> tuple[float, float]:
    """Constants (A, B) of log10 log10 Z = A - B log10 T (ASTM D341) through the kinematic
    viscosities ``nu1``, ``nu2`` [m^2/s] at the absolute temperatures ``t1``, ``t2`` [K]."""
    y1, y2 = math.log10(math.log10(float(d341_z(nu1)))), math.log10(math.log10(float(d341_z(nu2))))
    b = (y1 - y2) / (math.log10(t2) - math.log10(t1))
    return y1 + b * math.log10(t1), b


def walther_viscosity(a: float, b: float, t):
    """Kinematic viscosity [m^2/s] at the absolute temperature ``t`` [K] of the ASTM D341 line
    (A, B) (:func:`walther_constants`)."""
    return d341_nu(10.0 ** (10.0 ** (a - b * np.log10(np.asarray(t, float)))))


def iso_vg_viscosity(grade: int, temperature_c: float, key: str = "iso_vg") -> float:
    """Kinematic viscosity [m^2/s] of ISO VG ``grade`` at ``temperature_c`` [degC]: the ASTM D341
    line through its 40 and 100 degC viscosities (:data:`ISO_VG`).

    Raises
    ------
    ConfigError
        For an unknown grade, a temperature outside :data:`OIL_TEMPERATURE_RANGE_C` or a
        viscosity outside :data:`D341_VISCOSITY_RANGE`; ``key`` names the configuration key.
    """
    if grade not in ISO_VG:
        raise ConfigError(f"{key} = {grade!r}: unknown ISO VG grade; known (ISO 3448, VI "
                          f"{ISO_VG_VISCOSITY_INDEX} at 100 degC): {', '.join(map(str, ISO_VG))}")
    lo, hi = OIL_TEMPERATURE_RANGE_C
    if not (math.isfinite(temperature_c) and lo <= temperature_c <= hi):
        raise ConfigError(f"oil temperature {temperature_c!r} degC: outside the range flexgear applies the ASTM D341 "
                          f"viscosity relation in, [{lo:g}, {hi:g}] degC ({OIL_TEMPERATURE_REASON})")
    nu40, nu100 = ISO_VG[grade]
    a, b = walther_constants(40.0 + KELVIN, nu40, 100.0 + KELVIN, nu100)
    nu = float(walther_viscosity(a, b, temperature_c + KELVIN))
    if not D341_VISCOSITY_RANGE[0] <= nu <= D341_VISCOSITY_RANGE[1]:
        raise ConfigError(f"{key} = {grade}: kinematic viscosity {nu * 1e6:.4g} mm^2/s at {temperature_c:g} degC lies "
                          f"outside the range of ASTM D341's equations, 0.21 to 2e7 mm^2/s")
    return nu


@dataclass(frozen=True)
class Lubricant:
    """A gear oil at its operating (oil inlet) temperature.

    Attributes
    ----------
    viscosity : float
        Dynamic viscosity eta_0 at ambient pressure [Pa s].
    pressure_viscosity : float
        Barus pressure-viscosity coefficient alpha [1/Pa].
    density : float
        Density at the oil temperature [kg/m^3] (converts an ISO VG grade's kinematic viscosity).
    temperature_c : float or None
        Oil temperature [degC] (None: not given with a direct viscosity).
    iso_vg : int or None
        The ISO VG grade the viscosity was derived from (None: given directly).
    """

    viscosity: float
    pressure_viscosity: float
    density: float
    temperature_c: float | None = None
    iso_vg: int | None = None

    @classmethod
    def from_iso_vg(cls, grade: int, temperature_c: float, density: float, pressure_viscosity: float) -> "Lubricant":
        """ISO VG ``grade`` at ``temperature_c`` [degC] (:func:`iso_vg_viscosity`)."""
        nu = iso_vg_viscosity(grade, temperature_c, key="lubrication.iso_vg")
        return cls(viscosity=nu * density, pressure_viscosity=pressure_viscosity, density=density,
                   temperature_c=temperature_c, iso_vg=grade)

    @property
    def kinematic_viscosity(self) -> float:
        """nu = eta_0 / rho [m^2/s]."""
        return self.viscosity / self.density


# ============================================================================================
# friction model and lubrication of a gear set (the validated [lubrication] block)
# ============================================================================================
#: Mesh damping models: the IMPACT damper of [contact], or the EHL squeeze film.
DAMPING_MODELS = ("impact", "squeeze_film")


@dataclass(frozen=True)
class Lubrication:
    """Tooth friction and lubrication of a gear set (``Config.lubrication``).

    Attributes
    ----------
    friction_model : str
        ``"constant"`` (Coulomb), ``"benedict_kelley"`` or ``"xu"`` (:data:`~flexgear.gears.tribology.FRICTION_MODELS`).
    friction_coefficient : float or None
        Coulomb coefficient mu [-] (constant model only).
    sliding_speed_scale : float
        v_0 [m/s] of the regularisation mu tanh(v_s / v_0) at the pitch point.
    lubricant : Lubricant or None
        None only with the constant model (no film thickness, no squeeze film then).
    roughness : float or None
        Composite RMS roughness sqrt(Rq_a^2 + Rq_b^2) [m] of every mesh.
    gear_roughness : tuple of (gear, Rq [m]) or None
        RMS roughness per gear, instead of ``roughness``.
    damping : str
        ``"impact"`` or ``"squeeze_film"`` (:data:`DAMPING_MODELS`).
    xu_coefficients : tuple of 9 floats or None
        b_1 ... b_9 of the xu model (default :data:`~flexgear.gears.tribology.XU_2007`).
    """

    friction_model: str
    friction_coefficient: float | None = None
    sliding_speed_scale: float = 0.01
    lubricant: Lubricant | None = None
    roughness: float | None = None
    gear_roughness: tuple | None = None
    damping: str = "impact"
    xu_coefficients: tuple | None = None

    def mesh_roughness(self, gear_a: str, gear_b: str) -> float | None:
        """Composite RMS roughness [m] of the mesh between the gears named ``gear_a`` and
        ``gear_b`` (None when no roughness was given)."""
        if self.gear_roughness is not None:
            g = dict(self.gear_roughness)
            return math.hypot(g[gear_a], g[gear_b])
        return self.roughness


# ============================================================================================
# kinematics of a contact point
# ============================================================================================
def roll_angles(pair, s):
    """Roll angles (xi_1, xi_2) [rad] of the contact at ``s`` [m] along the line of action
    (module docstring); arrays broadcast."""
    s = np.asarray(s, float)
    t = math.tan(pair.alpha_w)
    rho1 = pair.g1.rb * t + s
    rho2 = pair.g2.rb * t + (s if pair.internal else -s)
    return rho1 / pair.g1.rb, rho2 / pair.g2.rb


def surface_speeds(rb1: float, xi1, omega1, rb2: float, xi2, omega2, internal: bool):
    """Speeds (u_1, u_2) [m/s] of the two flank surfaces along the common tangent at a contact,
    from the base radii [m], the roll angles [rad] and the angular velocities [rad/s] (signed,
    counter-clockwise positive, relative to the frame the centres stand still in): u_i =
    omega_i r_bi xi_i, with the sign of gear 2 turned for an external pair (its centre lies on
    the other side of the line of action), so that u_1 = u_2 in pure rolling."""
    u1 = np.asarray(omega1) * rb1 * np.asarray(xi1)
    u2 = np.asarray(omega2) * rb2 * np.asarray(xi2)
    return u1, (u2 if internal else -u2)


def pair_speeds(pair, s, omega1):
    """Sliding speed v_s = u_2 - u_1 and entrainment speed u_e = (u_1 + u_2) / 2 [m/s] of the
    contact at ``s`` [m] of a pair turning rigidly, gear 1 at ``omega1`` [rad/s] (gear 2 at
    omega_1 z_1 / z_2, opposite in an external pair). v_s = -omega_1 s (1 +- z_1 / z_2): zero
    at the pitch point, of the sign of -s omega_1 elsewhere. The sign is the results' (the
    recorded ``sliding_speed``, t . (V_1 - V_2) with the flank tangent t against gear 1's rolling
    motion on the loaded flank), so that mu(v_s) is signed like ``pair_friction_force /
    pair_force``; the losses take |v_s|."""
    xi1, xi2 = roll_angles(pair, s)
    omega2 = omega1 * pair.g1.z / pair.g2.z * (1.0 if pair.internal else -1.0)
    u1, u2 = surface_speeds(pair.g1.rb, xi1, omega1, pair.g2.rb, xi2, omega2, pair.internal)
    return u2 - u1, 0.5 * (u1 + u2)


def involute_contact_limits(pair) -> tuple[float, float]:
    """The positions (s_start, s_end) [m] on the line of action between which both flanks at the
    contact are involute: each gear's involute radius of curvature rho_i = r_bi xi_i
    (:func:`roll_angles`) between its form circle's and its tip circle's, sqrt(r^2 - r_bi^2)
    (an internal gear's involute runs outwards from its tip circle to its form circle). On gears
    without interference this is the ISO 21771 path of contact (-g_f, g_a); outside it one of the
    flanks is a tip corner (or the fillet), where the line-contact formulas of the involutes do
    not hold (guide page *Lubrication*, *Film thickness outputs*)."""
    arm1, arm2 = pair.g1.rb * math.tan(pair.alpha_w), pair.g2.rb * math.tan(pair.alpha_w)

    def rho(g, r):  # involute radius of curvature at radius r (0 below the base circle)
        return math.sqrt(max(r * r - g.rb * g.rb, 0.0))

    lo1, hi1 = rho(pair.g1, pair.g1.r_form) - arm1, rho(pair.g1, pair.g1.ra) - arm1  # rho_1 = arm1 + s
    if pair.internal:  # rho_2 = arm2 + s, from the tip circle (inside) to the form circle (outside)
        lo2, hi2 = rho(pair.g2, pair.g2.ra) - arm2, rho(pair.g2, pair.g2.r_form) - arm2
    else:  # rho_2 = arm2 - s
        lo2, hi2 = arm2 - rho(pair.g2, pair.g2.ra), arm2 - rho(pair.g2, pair.g2.r_form)
    return max(lo1, lo2), min(hi1, hi2)


def relative_radius(pair, s):
    """Relative radius of curvature R [m] of the involutes at ``s``: rho_1 rho_2 / (rho_2 -+
    rho_1) (+ external, - internal), rho_i = r_bi xi_i."""
    xi1, xi2 = roll_angles(pair, s)
    r1, r2 = pair.g1.rb * xi1, pair.g2.rb * xi2
    return r1 * r2 / (r2 - r1) if pair.internal else r1 * r2 / (r1 + r2)


# ============================================================================================
# mesh losses
# ============================================================================================
def _contact_ratios(pair) -> tuple[float, float, float]:
    gf, ga = pair.path_of_contact
    pb = pair.g1.pb
    return (gf + ga) / pb, ga / pb, gf / pb


def loss_factor(pair) -> float:
    """Tooth loss factor H_V [-] of a spur pair (Niemann & Winter, Maschinenelemente II, 1989,
    after Ohlendorf 1958; ISO/TR 14179-2:2001)::

        H_V = pi (u + 1) / (z_1 u) (1 - eps_alpha + eps_1^2 + eps_2^2)

    u = z_2 / z_1 (negative for an internal gear), eps_1 = g_a / p_b and eps_2 = g_f / p_b the
    addendum contact ratios of gear 1 and gear 2 (ISO 21771 path of contact). The mesh power
    loss is P_V = mu H_V P_in for a constant coefficient mu, the mesh efficiency 1 - mu H_V. It
    is the sliding power mu F |v_s| averaged over a mesh cycle with the load F shared equally by
    two pairs and carried whole by one (:func:`ideal_pair_loads`), divided by F omega_1 r_b1.

    Raises
    ------
    GeometryError
        Outside the formula's derivation: eps_alpha not in [1, 2) or an addendum contact ratio
        above 1.
    """
    eps, e1, e2 = _contact_ratios(pair)
    if not (1.0 <= eps < 2.0 and e1 <= 1.0 and e2 <= 1.0):
        raise GeometryError(f"pair {pair.name}: eps_alpha = {eps:.4g}, eps_1 = {e1:.4g}, eps_2 = {e2:.4g}: the loss "
                            "factor H_V holds for 1 <= eps_alpha < 2 with eps_1, eps_2 <= 1 (use path_losses)")
    u = pair.g2.z / pair.g1.z * (-1.0 if pair.internal else 1.0)
    return math.pi * (u + 1.0) / (pair.g1.z * u) * (1.0 - eps + e1 * e1 + e2 * e2)


def ideal_pair_loads(pair, s, load: float, limits=None):
    """Loads [N] of the pairs at s, s + p_b, s + 2 p_b, ... (columns) when ``load`` [N] is
    shared equally by the pairs on the path of contact (the load sharing of :func:`loss_factor`).
    ``limits`` = (s_start, s_end) [m], default the ISO 21771 path (-g_f, g_a)."""
    s = np.asarray(s, float)
    gf, ga = pair.path_of_contact
    lo, hi = (-gf, ga) if limits is None else limits
    pb = pair.g1.pb
    npairs = int(math.ceil((hi - lo) / pb)) + 1
    pos = s[:, None] + pb * np.arange(npairs)[None, :]
    on = (pos >= lo) & (pos <= hi)
    n = on.sum(axis=1, keepdims=True)
    return np.where(on, load / np.maximum(n, 1), 0.0)


@dataclass
class PathLosses:
    """Friction losses of a mesh over one mesh cycle (:func:`path_losses`).

    Attributes
    ----------
    s : ndarray (N,)
        Mesh positions: the first pair's contact position [m]; pair j sits at s + j p_b.
    mu, sliding_speed, entrainment_speed, radius : ndarray (N, P)
        Friction coefficient [-], v_s and u_e [m/s], relative radius [m] of each pair.
    power : ndarray (N,)
        Friction power sum_j |mu_j| F_j |v_s,j| [W] at each position.
    input_power : float
        F omega_1 r_b1 [W].
    """

    s: np.ndarray
    mu: np.ndarray
    sliding_speed: np.ndarray
    entrainment_speed: np.ndarray
    radius: np.ndarray
    power: np.ndarray
    input_power: float

    @property
    def mean_power(self) -> float:
        """Friction power averaged over the mesh cycle [W] (positions uniformly spaced)."""
        return float(np.mean(self.power))

    @property
    def efficiency(self) -> float:
        """Mesh efficiency 1 - P_V / P_in [-]."""
        return 1.0 - self.mean_power / self.input_power


def path_losses(pair, s, pair_loads, load: float, omega1: float, coefficient) -> PathLosses:
    """Friction power of a mesh integrated along its path of contact.

    Parameters
    ----------
    pair : GearPair
    s : array (N,)
        Positions over one mesh cycle [m], uniformly spaced (the mean over them is the cycle mean).
    pair_loads : array (N, P)
        Normal loads [N] of the pairs at s + j p_b (0 off the path).
    load : float
        Total normal load F along the line of action [N]: the input power is F omega_1 r_b1.
    omega1 : float
        Angular velocity of gear 1 [rad/s].
    coefficient : callable
        ``coefficient(v_s, u_e, load_per_width, R)`` -> mu [-] (arrays; e.g.
        :meth:`flexgear.gears.tribology.FrictionLaw.coefficient`).
    """
    s = np.asarray(s, float)
    F = np.asarray(pair_loads, float)
    pos = s[:, None] + pair.g1.pb * np.arange(F.shape[1])[None, :]
    vs, ue = pair_speeds(pair, pos, omega1)
    R = relative_radius(pair, pos)
    L = pair.face_width
    on = F > 0
    mu = np.zeros_like(F)
    if np.any(on):
        mu[on] = coefficient(vs[on], ue[on], F[on] / L, R[on])
    power = np.sum(np.abs(mu) * F * np.abs(vs), axis=1)
    return PathLosses(s=s, mu=mu, sliding_speed=vs, entrainment_speed=ue, radius=R, power=power,
                      input_power=abs(load * omega1 * pair.g1.rb))


# ============================================================================================
# the nominal operating point of a mesh (flexgear info)
# ============================================================================================
@dataclass(frozen=True)
class NominalLubrication:
    """A mesh turning rigidly at its static load (:func:`nominal_lubrication`): the loss factor
    H_V (None outside its range), the mesh efficiency with the pairs sharing the load equally,
    and at the pitch point the sliding-free contact's load per face width [N/m], central and
    minimum film thickness [m] and film thickness ratio lambda (None without a lubricant or a
    roughness)."""

    loss_factor: float | None
    efficiency: float
    pitch_load: float
    film_central: float | None
    film_minimum: float | None
    film_ratio: float | None


def nominal_lubrication(pair, law, lubricant: Lubricant | None, roughness: float | None, e_star: float,
                        load: float, omega1: float, positions: int = 400) -> NominalLubrication:
    """The mesh ``pair`` at the static normal load ``load`` [N] along the line of action, gear 1
    at ``omega1`` [rad/s] relative to the frame its centre stands still in: :func:`path_losses`
    over ``positions`` positions of one base pitch with :func:`ideal_pair_loads` (``law``: a
    :class:`~flexgear.gears.tribology.FrictionLaw`), and the pitch point's EHL film
    (:func:`~flexgear.gears.tribology.central_film_thickness`, ``minimum_film_thickness``) at
    the load share the pair there carries."""
    gf, _ = pair.path_of_contact
    pb = pair.g1.pb
    s = -gf + pb * np.arange(positions) / positions  # one mesh cycle
    losses = path_losses(pair, s, ideal_pair_loads(pair, s, load), load, omega1, law.coefficient)
    try:
        hv = loss_factor(pair)
    except GeometryError:
        hv = None
    j = math.floor(gf / pb)  # the pairs from the first on the path, at s = -j p_b, to the pitch point's
    w = float(ideal_pair_loads(pair, np.array([-j * pb]), load)[0, j]) / pair.face_width
    hc = hm = lam = None
    if lubricant is not None:
        _, ue = pair_speeds(pair, 0.0, omega1)
        R = float(relative_radius(pair, 0.0))
        args = (abs(float(ue)), lubricant.viscosity, lubricant.pressure_viscosity, w, R, e_star)
        hc, hm = float(central_film_thickness(*args)), float(minimum_film_thickness(*args))
        lam = hm / roughness if roughness else None
    return NominalLubrication(hv, losses.efficiency, w, hc, hm, lam)
