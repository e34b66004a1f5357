"""Tooth stiffness of spur and helical gear pairs after ISO 6336-1:2019, clause 9, method B.

* q' = C1 + C2/z_n1 + C3/z_n2 + C4 x1 + C5 x1/z_n1 + C6 x2 + C7 x2/z_n2 + C8 x1^2 + C9 x2^2
  [mm um/N], C1..C9 = 0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188,
  0.00529, 0.00182; index 1 the pinion (internal pair: the external gear); z_n the virtual
  number of teeth. For an internal gear ISO sets z_n2 = infinity (a rack): C3 and C7 terms vanish.
* ``c' = c'_th C_M C_R C_B cos(beta)``, c'_th = 1/q', with C_M = 0.8 (solid discs), the gear
  blank factor C_R (1 for solid discs) and the basic rack factor C_B (0.975 for the standard
  rack; the mean of both gears' for two racks); below a line load of 100 N/mm c' is multiplied
  by ((F_t K_A/b)/(100 N/mm))^0.25.
* ``c_gamma_alpha = c' (0.75 eps_alpha + 0.25)`` (eps_alpha >= 1.2); c_gamma_beta = 0.85
  c_gamma_alpha for helical gears, returned for completeness.

Units: ISO's N/(mm um) are per mm of face width per um along the line of action; here stiffness
is SI per metre of face width, N/m^2 (1 N/(mm um) = 1e9 N/m^2; :func:`to_iso_units`,
:func:`from_iso_units`). q' stays in mm um/N, the units of the regression (:func:`q_prime_si`:
m^2/N). The tests reproduce the worked example of ISO/TR 6336-30:2017.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError

#: 1 N/(mm um) expressed in SI (N/m per metre of face width = N/m^2).
N_PER_MM_UM = 1.0e9

#: ISO 6336-1 method B coefficients C1..C9 of q' [mm um/N].
C_COEFFS = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)

#: ISO 6336-1 correction factor theory/measurement for solid disc gears.
C_M_SOLID = 0.8

#: Line load [N/m] above which ISO uses c' without the low-load reduction (100 N/mm).
LINE_LOAD_REF = 1.0e5


def to_iso_units(c_si: float) -> float:
    """Convert a stiffness per face width from SI N/m^2 to ISO N/(mm um)."""
    return c_si / N_PER_MM_UM


def from_iso_units(c_iso: float) -> float:
    """Convert a stiffness per face width from ISO N/(mm um) to SI N/m^2."""
    return c_iso * N_PER_MM_UM


def virtual_teeth(z: float, beta: float = 0.0, alpha_n: float = math.radians(20.0)) -> float:
    """Virtual number of teeth z_n = z / (cos^2(beta_b) cos(beta)) [-].

    Parameters
    ----------
    z : float
        Number of teeth [-] (positive, also for internal gears).
    beta : float
        Helix angle at the reference cylinder [rad]; 0 for spur gears (then z_n = z).
    alpha_n : float
        Normal pressure angle [rad].
    """
    beta_b = math.asin(math.sin(beta) * math.cos(alpha_n))
    return z / (math.cos(beta_b) ** 2 * math.cos(beta))


def q_prime(z_n1: float, z_n2: float, x1: float = 0.0, x2: float = 0.0) -> float:
    """Minimum flexibility of a pair of teeth q' [mm um/N] (ISO 6336-1 method B).

    Parameters
    ----------
    z_n1, z_n2 : float
        Virtual numbers of teeth of pinion and wheel [-]; ``math.inf`` for z_n2 gives the
        internal-gear (rack) case.
    x1, x2 : float
        Profile shift coefficients of pinion and wheel [-].
    """
    c1, c2, c3, c4, c5, c6, c7, c8, c9 = C_COEFFS
    inv1 = 1.0 / z_n1
    inv2 = 0.0 if math.isinf(z_n2) else 1.0 / z_n2
    return (c1 + c2 * inv1 + c3 * inv2 + c4 * x1 + c5 * x1 * inv1 + c6 * x2 + c7 * x2 * inv2
            + c8 * x1 ** 2 + c9 * x2 ** 2)


def q_prime_si(z_n1: float, z_n2: float, x1: float = 0.0, x2: float = 0.0) -> float:
    """q' in SI: compliance per unit face width [m^2/N] (= q'[mm um/N] * 1e-9)."""
    return q_prime(z_n1, z_n2, x1, x2) / N_PER_MM_UM


def basic_rack_factor(h_fP: float = 1.25, alpha_Pn: float = math.radians(20.0)) -> float:
    """Basic rack factor C_B of one gear [-].

    Parameters
    ----------
    h_fP : float
        Dedendum of the basic rack divided by the normal module, h_fP/m_n [-].
    alpha_Pn : float
        Normal pressure angle of the basic rack [rad].
    """
    return (1.0 + 0.5 * (1.2 - h_fP)) * (1.0 - 0.02 * (20.0 - math.degrees(alpha_Pn)))


def gear_blank_factor(b_s_over_b: float = 1.0, s_R_over_mn: float | None = None) -> float:
    """Gear blank factor C_R [-]: 1 for solid disc gears.

    Parameters
    ----------
    b_s_over_b : float
        Web thickness over face width [-]; 1 for a solid disc (then C_R = 1).
    s_R_over_mn : float, optional
        Rim thickness over normal module [-]; needed only when ``b_s_over_b != 1``.
    """
    if b_s_over_b == 1.0:
        return 1.0
    if not 0.2 <= b_s_over_b <= 1.2:
        raise ConfigError(f"b_s/b = {b_s_over_b!r}: ISO 6336-1 C_R is valid for 0.2 <= b_s/b <= 1.2")
    if s_R_over_mn is None or s_R_over_mn < 1.0:
        raise ConfigError(f"s_R/m_n = {s_R_over_mn!r}: ISO 6336-1 C_R needs a rim thickness >= 1 m_n")
    return 1.0 + math.log(b_s_over_b) / (5.0 * math.exp(s_R_over_mn / 5.0))


@dataclass(frozen=True)
class SingleStiffness:
    """ISO 6336-1 single stiffness of a tooth pair. Stiffnesses per face width in SI [N/m^2].

    Attributes
    ----------
    z_n1, z_n2 : float
        Virtual numbers of teeth used (pinion, wheel; ``inf`` for an internal wheel) [-].
    q_prime : float
        Minimum flexibility [mm um/N] (ISO units).
    c_th : float
        Theoretical single stiffness 1/q' [N/m^2].
    C_M, C_R, C_B : float
        Correction, gear blank and basic rack factors [-].
    low_load_factor : float
        ((F_t K_A/b)/(100 N/mm))^0.25 when the line load is below 100 N/mm, else 1 [-].
    c_prime : float
        Single stiffness c' [N/m^2].
    """

    z_n1: float
    z_n2: float
    q_prime: float
    c_th: float
    C_M: float
    C_R: float
    C_B: float
    low_load_factor: float
    c_prime: float

    @property
    def c_th_iso(self) -> float:
        """c'_th in N/(mm um)."""
        return to_iso_units(self.c_th)

    @property
    def c_prime_iso(self) -> float:
        """c' in N/(mm um)."""
        return to_iso_units(self.c_prime)


def single_stiffness(z1: int, z2: int, x1: float = 0.0, x2: float = 0.0, *, internal: bool = False,
                     beta: float = 0.0, alpha_n: float = math.radians(20.0), h_fP: float = 1.25,
                     alpha_Pn: float | None = None, h_fP2: float | None = None,
                     C_M: float = C_M_SOLID, b_s_over_b: float = 1.0,
                     s_R_over_mn: float | None = None,
                     line_load: float | None = None) -> SingleStiffness:
    """Single stiffness c' of a tooth pair after ISO 6336-1 method B.

    Parameters
    ----------
    z1, z2 : int
        Numbers of teeth [-] (positive). For an external pair the gear with fewer teeth is taken
        as the pinion (index 1), whatever the order given. For ``internal=True``, z1 is the
        external gear (pinion) and z2 the internal gear; then z_n2 = infinity (ISO rule).
    x1, x2 : float
        Profile shift coefficients belonging to z1 and z2 [-].
    internal : bool
        True for an internal gear pair.
    beta : float
        Helix angle [rad] (0: spur).
    alpha_n : float
        Normal pressure angle [rad] (for the virtual number of teeth).
    h_fP : float
        Basic rack dedendum / normal module [-] of both gears (1.25 standard rack).
    alpha_Pn : float, optional
        Basic rack pressure angle [rad]; defaults to ``alpha_n``.
    h_fP2 : float, optional
        Dedendum factor of gear 2 when its rack differs; C_B is then the mean of both gears.
    C_M : float
        Correction factor [-] (0.8, solid disc gears).
    b_s_over_b, s_R_over_mn : float
        Web and rim proportions for C_R (see :func:`gear_blank_factor`).
    line_load : float, optional
        F_t K_A / b [N/m]; when below 1e5 N/m (100 N/mm) c' is reduced by
        (line_load/1e5)^0.25. None: no reduction (the nominal c').

    Returns
    -------
    SingleStiffness
        c'_th and c' in N/m^2 (per metre face width) and the factors used.
    """
    if min(z1, z2) < 5:
        raise ConfigError(f"z1, z2 = {z1!r}, {z2!r}: numbers of teeth must be >= 5")
    if not 0.0 <= beta < math.radians(45.0):
        raise ConfigError(f"beta = {beta!r}: ISO 6336-1 method B needs 0 <= beta < 45 deg")
    if alpha_Pn is None:
        alpha_Pn = alpha_n
    if internal:
        zp, xp, zw, xw = z1, x1, z2, x2
        if zw <= zp:
            raise ConfigError(f"internal pair z1 = {z1}, z2 = {z2}: the internal gear needs more teeth")
        z_n1 = virtual_teeth(zp, beta, alpha_n)
        z_n2 = math.inf
    else:
        (zp, xp), (zw, xw) = sorted([(z1, x1), (z2, x2)], key=lambda t: t[0])
        z_n1 = virtual_teeth(zp, beta, alpha_n)
        z_n2 = virtual_teeth(zw, beta, alpha_n)
    q = q_prime(z_n1, z_n2, xp, xw)
    c_th = N_PER_MM_UM / q
    C_B1 = basic_rack_factor(h_fP, alpha_Pn)
    C_B2 = basic_rack_factor(h_fP if h_fP2 is None else h_fP2, alpha_Pn)
    C_B = 0.5 * (C_B1 + C_B2)
    C_R = gear_blank_factor(b_s_over_b, s_R_over_mn)
    low = 1.0
    if line_load is not None:
        if line_load <= 0:
            raise ConfigError(f"line_load = {line_load!r}: must be > 0 N/m")
        if line_load < LINE_LOAD_REF:
            low = (line_load / LINE_LOAD_REF) ** 0.25
    c_prime = c_th * C_M * C_R * C_B * math.cos(beta) * low
    return SingleStiffness(z_n1, z_n2, q, c_th, C_M, C_R, C_B, low, c_prime)


def mesh_stiffness(c_prime: float, eps_alpha: float) -> float:
    """Mean mesh stiffness c_gamma_alpha = c' (0.75 eps_alpha + 0.25), same units as c'.

    Parameters
    ----------
    c_prime : float
        Single stiffness [N/m^2] (or N/(mm um): the formula is unit-free).
    eps_alpha : float
        Transverse contact ratio [-]; ISO states the formula for eps_alpha >= 1.2.
    """
    if eps_alpha < 1.0:
        raise ConfigError(f"eps_alpha = {eps_alpha!r}: transverse contact ratio must be >= 1")
    return c_prime * (0.75 * eps_alpha + 0.25)


def transverse_contact_ratio(z1: int, z2: int, module: float,
                             alpha: float = math.radians(20.0), *, internal: bool = False,
                             ha: float = 1.0, x1: float = 0.0, x2: float = 0.0) -> float:
    """Transverse contact ratio of a spur pair at standard centre distance (ISO 21771) [-].

    eps_alpha = (g_a1 + g_a2) / p_b with the path of approach/recess limited by the tip circles:
    external: (sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a sin(alpha_w)) / p_b;
    internal: (sqrt(ra1^2 - rb1^2) - sqrt(ra2^2 - rb2^2) + a sin(alpha_w)) / p_b, where ra2 is the
    (inner) tip radius of the internal gear. Profile shift enters the tip radii only
    (x1 + x2 = 0 assumed, so the centre distance stays the standard one).

    Parameters
    ----------
    z1, z2 : int
        Numbers of teeth (z1 external; z2 internal when ``internal``) [-].
    module : float
        Module [m].
    alpha : float
        Pressure angle [rad].
    ha : float
        Addendum coefficient [-].
    x1, x2 : float
        Profile shift coefficients [-].
    """
    r1, r2 = 0.5 * module * z1, 0.5 * module * z2
    rb1, rb2 = r1 * math.cos(alpha), r2 * math.cos(alpha)
    pb = math.pi * module * math.cos(alpha)
    ra1 = r1 + module * (ha + x1)
    if internal:
        ra2 = r2 - module * (ha - x2)
        a = r2 - r1
        g = math.sqrt(ra1 ** 2 - rb1 ** 2) - math.sqrt(ra2 ** 2 - rb2 ** 2) + a * math.sin(alpha)
    else:
        ra2 = r2 + module * (ha + x2)
        a = r1 + r2
        g = math.sqrt(ra1 ** 2 - rb1 ** 2) + math.sqrt(ra2 ** 2 - rb2 ** 2) - a * math.sin(alpha)
    return g / pb


@dataclass(frozen=True)
class PairStiffness:
    """ISO 6336-1 stiffness of a spur pair, per face width and for the given face width.

    Attributes
    ----------
    single : SingleStiffness
        c' and its factors.
    eps_alpha : float
        Transverse contact ratio used [-].
    c_gamma_alpha : float
        Mean mesh stiffness per face width [N/m^2].
    face_width : float
        Face width [m].
    k_single : float
        c' times face width [N/m]: stiffness of one tooth pair (maximum single-pair value).
    k_mesh : float
        c_gamma_alpha times face width [N/m]: mean mesh stiffness.
    """

    single: SingleStiffness
    eps_alpha: float
    c_gamma_alpha: float
    face_width: float

    @property
    def c_prime(self) -> float:
        """c' [N/m^2]."""
        return self.single.c_prime

    @property
    def k_single(self) -> float:
        """c' b [N/m]."""
        return self.single.c_prime * self.face_width

    @property
    def k_mesh(self) -> float:
        """c_gamma_alpha b [N/m]."""
        return self.c_gamma_alpha * self.face_width


def pair_stiffness(z1: int, z2: int, module: float, face_width: float, *,
                   internal: bool = False, alpha: float = math.radians(20.0), x1: float = 0.0,
                   x2: float = 0.0, ha: float = 1.0, hf: float = 1.25,
                   eps_alpha: float | None = None, line_load: float | None = None,
                   C_M: float = C_M_SOLID) -> PairStiffness:
    """ISO 6336-1 c' and c_gamma_alpha of a spur pair (solid disc gears, standard rack).

    Parameters
    ----------
    z1, z2 : int
        Numbers of teeth [-]; for ``internal`` z2 is the internal gear.
    module : float
        Module [m].
    face_width : float
        Common face width [m].
    internal : bool
        Internal pair (z_n2 = infinity in q').
    alpha : float
        Pressure angle [rad].
    x1, x2 : float
        Profile shift coefficients [-].
    ha, hf : float
        Addendum and dedendum coefficients of the basic rack [-] (hf = h_fP/m for C_B).
    eps_alpha : float, optional
        Transverse contact ratio; computed with :func:`transverse_contact_ratio` when omitted.
    line_load : float, optional
        F_t K_A / b [N/m] for the ISO low-load reduction (see :func:`single_stiffness`).
    C_M : float
        Correction factor [-].

    Examples
    --------
    MERCURY 1-A sun-planet (24/21, m = 2 mm, b = 20 mm)::

        >>> p = pair_stiffness(24, 21, 2e-3, 0.02)
        >>> round(to_iso_units(p.c_prime), 2), round(p.eps_alpha, 3)
        (11.93, 1.586)
    """
    if not face_width > 0:
        raise ConfigError(f"face_width = {face_width!r}: must be > 0 m")
    if eps_alpha is None:
        eps_alpha = transverse_contact_ratio(z1, z2, module, alpha, internal=internal, ha=ha,
                                             x1=x1, x2=x2)
    single = single_stiffness(z1, z2, x1, x2, internal=internal, alpha_n=alpha, h_fP=hf,
                              line_load=line_load, C_M=C_M)
    return PairStiffness(single, eps_alpha, mesh_stiffness(single.c_prime, eps_alpha), face_width)
