"""Contact laws: the ADAMS IMPACT law of a rigid tooth pair, the 2D Hertz line contact of compliant
flanks, and the loads and penetration gradient of a contact force on two bodies.

IMPACT (MSC ADAMS, the paper's Eqs. (3)-(4); docs/paper_parameters.md)::

    F = max(0, K delta^e + STEP(delta; 0, 0, d, C) * d(delta)/dt)   for delta > 0, else 0
    STEP(x; x0, h0, x1, h1) = h0 + (h1 - h0) D^2 (3 - 2 D),  D = (x - x0)/(x1 - x0) clipped to [0, 1]
"""
from __future__ import annotations

import math

from ...kernels import kernel

#: the contact law of a mesh (``MeshTable.law``): IMPACT, or line-contact Hertz on compliant flanks
LAW_IMPACT, LAW_HERTZ = 0, 1



@kernel(literal=True, error_model="numpy")
def step(x, x0, h0, x1, h1):
    """ADAMS STEP function (cubic): h0 for x <= x0, h1 for x >= x1, smooth in between."""
    if x <= x0:
        return h0
    if x >= x1:
        return h1
    D = (x - x0) / (x1 - x0)
    return h0 + (h1 - h0) * D * D * (3.0 - 2.0 * D)


@kernel(literal=True, error_model="numpy")
def step_derivative(x, x0, h0, x1, h1):
    """d STEP / dx."""
    if x <= x0 or x >= x1:
        return 0.0
    D = (x - x0) / (x1 - x0)
    return (h1 - h0) * 6.0 * D * (1.0 - D) / (x1 - x0)


@kernel(literal=True, error_model="numpy")
def impact_force(delta, delta_dot, K, e, C, d):
    """ADAMS IMPACT contact force and its partial derivatives.

    Parameters
    ----------
    delta : float
        Penetration [m] (> 0 when the bodies overlap).
    delta_dot : float
        Penetration rate [m/s] (> 0 while approaching).
    K, e, C, d : float
        Stiffness [N/m^e], exponent [-], maximum damping [N s/m], penetration at full damping [m].

    Returns
    -------
    F, dF/ddelta, dF/ddelta_dot : float
        Force [N] (never negative) and its derivatives.
    """
    if delta <= 0.0:
        return 0.0, 0.0, 0.0
    s = step(delta, 0.0, 0.0, d, C)
    F = K * delta**e + s * delta_dot
    if F <= 0.0:
        return 0.0, 0.0, 0.0
    dF = K * e * delta ** (e - 1.0) + step_derivative(delta, 0.0, 0.0, d, C) * delta_dot
    return F, dF, s


@kernel(literal=True, error_model="numpy", inline="always")
def contact_load(Fb, pose, a, b, px, py, nx, ny, F):
    """Add a contact force F [N] along the unit normal (nx, ny), acting at (px, py), to body a
    and its reaction to body b (rows of Fb: fx, fy, moment about the body's reference point).

    Returns
    -------
    ma, mb : float
        Moment arms [m] of the normal about a's and b's reference points.
    """
    ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
    mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
    Fb[a, 0] += F * nx
    Fb[a, 1] += F * ny
    Fb[a, 2] += F * ma
    Fb[b, 0] -= F * nx
    Fb[b, 1] -= F * ny
    Fb[b, 2] -= F * mb
    return ma, mb


@kernel(literal=True, error_model="numpy", inline="always")
def penetration_gradient(g, J, a, b, nx, ny, ma, mb, n):
    """g[j] = d(penetration)/dq_j of a contact with normal (nx, ny) and moment arms ma, mb,
    from the pose Jacobians J[body, (x, y, theta), j]."""
    for j in range(n):
        g[j] = -(nx * J[a, 0, j] + ny * J[a, 1, j] + ma * J[a, 2, j]) + (
            nx * J[b, 0, j] + ny * J[b, 1, j] + mb * J[b, 2, j])


@kernel(literal=True, error_model="numpy")
def hertz_line(F, R, L, ka, na, da, kb, nb_, db, es):
    """2D Hertz line-contact approach between the reference depths and its derivative.

    ``h = P [ka (2 ln(2 da/a) - 1/2 - na) + kb (2 ln(2 db/a) - 1/2 - nb) + 1/(2 pi E*)]``,
    P = F / L, a = sqrt(4 P R / (pi E*)) (:func:`flexgear.stiffness.hertz.hertz_approach`).

    Parameters
    ----------
    F : float
        Normal force [N] (> 0).
    R : float
        Relative radius of curvature [m].
    L : float
        Contact length [m].
    ka, kb : float
        1 / (pi E1) of each body [1/Pa].
    na, nb_ : float
        nu1 of each body [-].
    da, db : float
        Reference depths [m].
    es : float
        Contact modulus E* [Pa].

    Returns
    -------
    h, dh/dF : float
        Approach [m] and compliance [m/N].
    """
    P = max(F, 1e-9) / L  # a force below 1 nN: evaluated at 1 nN (no log(0))
    a = math.sqrt(4.0 * P * R / (math.pi * es))
    la = math.log(2.0 * da / a)
    lb = math.log(2.0 * db / a)
    c0 = 1.0 / (2.0 * math.pi * es)
    h = P * (ka * (2.0 * la - 0.5 - na) + kb * (2.0 * lb - 0.5 - nb_) + c0)
    dh = (ka * (2.0 * la - 1.5 - na) + kb * (2.0 * lb - 1.5 - nb_) + c0) / L
    return h, dh


#: Columns of a compliant contact's row in ``contacts.hertz``: 0-8 the arguments of
#: :func:`hertz_line`, then the per-tooth terms: the series compliance [m/N] and each flank's
#: outline width fraction and recess [m] (A, then B).
HERTZ_SERIES, HERTZ_WIDTH_A, HERTZ_RECESS_A, HERTZ_WIDTH_B, HERTZ_RECESS_B = 9, 10, 11, 12, 13
HERTZ_COLUMNS = 14
#: The per-tooth terms (columns HERTZ_SERIES to HERTZ_RECESS_B) of a healthy contact.
HEALTHY_TERMS = (0.0, 1.0, 0.0, 1.0, 0.0)


@kernel(error_model="numpy", inline="always")
def bracketed(x, lo, hi):
    """A Newton iterate ``x`` kept inside the bracket (lo, hi): itself, else the midpoint."""
    return x if lo < x < hi else 0.5 * (lo + hi)


@kernel(error_model="numpy")
def hertz_force(x, hp, i):
    """(P, dh/dF at P): the force P [N] of the whole-width Hertz line contact of row i whose
    approach :func:`hertz_line` is x [m] (> 0); Newton's method inside a bracket (h increasing)."""
    lo = 0.0
    hi = 1.0
    for _ in range(80):
        h, _ = hertz_line(hi, hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6], hp[i, 7], hp[i, 8])
        if h >= x:
            break
        lo = hi
        hi *= 2.0
    P = 0.5 * (lo + hi)
    dh = 1.0
    for _ in range(200):
        h, dh = hertz_line(P, hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6], hp[i, 7], hp[i, 8])
        if h < x:
            lo = P
        else:
            hi = P
        Pn = bracketed(P - (h - x) / dh, lo, hi)
        if abs(Pn - P) <= 1e-14 * P:
            return Pn, dh
        P = Pn
    return P, dh


@kernel(error_model="numpy")
def slice_approach(F, hp, i):
    """Approach [m] and dh/dF [m/N] of contact i whose flanks carry a fault over part of the face
    width: slices in parallel with a common approach a (the plane FE compliance acts on the total
    force), the outline's part ``w`` of each flank at the outline, the rest ``recess`` below it
    (:func:`flexgear.gears.modified.partial_width_force`): slice s of width w_s carries
    w_s P(a - recess_s), P the inverse of the whole-width Hertz approach; a is the root of
    sum_s w_s P(a - recess_s) = F (Newton inside a bracket), dh/dF = 1 / sum_s w_s / h'(P_s)."""
    wa = hp[i, HERTZ_WIDTH_A]
    ra = hp[i, HERTZ_RECESS_A]
    wb = hp[i, HERTZ_WIDTH_B]
    rb = hp[i, HERTZ_RECESS_B]
    w0 = wa * wb  # the outline slice of both flanks: recess 0
    lo = 0.0
    hi, _ = hertz_line(F / w0, hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6], hp[i, 7], hp[i, 8])
    a = hi
    da = 1.0
    for _ in range(200):
        G = 0.0
        dG = 0.0
        for sl in range(4):
            w = (wa if sl % 2 == 0 else 1.0 - wa) * (wb if sl < 2 else 1.0 - wb)
            x = a - ((0.0 if sl % 2 == 0 else ra) + (0.0 if sl < 2 else rb))
            if w <= 0.0 or x <= 0.0:
                continue
            P, dh = hertz_force(x, hp, i)
            G += w * P
            dG += w / dh
        if G < F:
            lo = a
        else:
            hi = a
        da = 1.0 / dG if dG > 0.0 else 0.0
        an = bracketed(a - (G - F) * da, lo, hi)
        if abs(an - a) <= 1e-14 * a:
            return an, da
        a = an
    return a, da


@kernel(literal=True, error_model="numpy")
def contact_approach(F, hp, i):
    """Elastic approach of contact i of the compliant law and its derivative: the Hertz line
    contact :func:`hertz_line` of ``hp[i, 0:9]`` (with a fault over part of either flank's face
    width, an outline width fraction not 1: the slices of :func:`slice_approach`) plus the series
    compliance ``hp[i, HERTZ_SERIES]`` [m/N] times F (a root crack:
    :mod:`flexgear.dynamics.model.tooth_laws`; 0.0 on healthy teeth, which adds exactly nothing).

    Returns
    -------
    h, dh/dF : float
        Approach [m] and compliance [m/N].
    """
    s = hp[i, HERTZ_SERIES]
    if hp[i, HERTZ_WIDTH_A] != 1.0 or hp[i, HERTZ_WIDTH_B] != 1.0:  # the per-tooth table's slices
        h, dh = slice_approach(max(F, 1e-9), hp, i)
        return h + s * F, dh + s
    h, dh = hertz_line(F, hp[i, 0], hp[i, 1], hp[i, 2], hp[i, 3], hp[i, 4], hp[i, 5], hp[i, 6], hp[i, 7], hp[i, 8])
    return h + s * F, dh + s
