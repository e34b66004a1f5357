"""Condensed modes integrated inside the contact solve: the modes' own inertia at no Newton cost.

A flexible gear's modes above ``[flexible] dynamic_cutoff`` are not coordinates of the Newton
system. Each obeys ``eta_i'' + c_i eta_i' + omega_i^2 eta_i = A_i . F + l_i`` (l_i the frame's
inertia load); within an HHT-alpha step its end acceleration is affine in the end loads::

    eta_i'' D_i = (1 + alpha) A_i . F + f_i + l_i
    D_i = 1 + (1 + alpha) (c_i gamma h + omega_i^2 beta h^2)
    f_i = (1 + alpha) (-c_i v^_i - omega_i^2 x^_i) + alpha P_i

(x^, v^ the Newmark predictors, P_i = c_i eta_i' + omega_i^2 eta_i - A_i . F at the accepted
step), so the flank displacement is a compliance of the quasi-static form with each mode
weighted by ``kappa_i = (1 + alpha) beta h^2 omega_i^2 / D_i``, plus the modes' history and the
frame's inertia load: :mod:`flexgear.dynamics.flexible.compliant` solves the contact problem
with it on the same unknowns. The frame receives the modes' reaction (outside the HHT
weighting: ``SystemMatrices.inertia_load``), which keeps the Newton matrix symmetric. This is a
Schur complement of the modes as coordinates, exact at any step; quasi-static condensation is
the limit omega_i h >> 1. See the theory page *Compliant contact and condensation*.

The state (eta, eta', eta'', P per mode) lives in the workspace's
:class:`flexgear.dynamics.integrator.buffers.CondensedState` and advances when the integrator
accepts a step (:func:`accept_condensed`).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels import kernel

from ..integrator.hht import hht_coefficients, predict

STATIC, INTEGRATED = 0, 1

#: relative difference below which two steps are the same step for the coefficients that
#: depend on it alone (:func:`condensed_coefficients`): the integrator's step t_target - t
#: differs from the nominal step by the round-off of t (about 1e-13 relative)
STEP_ROUNDOFF = 1e-9

#: share of its static response that a mode must give within one step for the reduction's
#: residual flexibility (the modes above the cutoff, static tables) to stand for it
STATIC_SHARE = 0.94


def static_frequency(h: float, alpha: float = -0.1, share: float = STATIC_SHARE) -> float:
    """Frequency [Hz] above which an undamped mode integrated with HHT-alpha at step h [s]
    responds to a load within the step with at least ``share`` of its static response (kappa_i
    of the module docstring; 1.21 / h at the defaults: 194 kHz at 6.25 us, 48 kHz at 25 us).
    Modes above the reduction's cutoff are condensed statically into the residual tables; a
    cutoff below this frequency leaves modes that the step resolves to those static tables.
    On the flexible spur pair at 6.25 us (level 1, 5 % damping, against the full-order FE) a
    100 kHz cutoff puts the 4080 Hz line 2.1 % and the force RMS about the mean 3.2 % off, a 200
    kHz cutoff 1.6 % and 1.6 %, 400 kHz 1.5 % and 1.5 %."""
    beta, _ = hht_coefficients(alpha)
    x2 = share / ((1.0 - share) * (1.0 + alpha) * beta)
    return math.sqrt(x2) / (2.0 * math.pi * h)


class ModeViews(NamedTuple):
    """One flexible body's condensed modes: views of the per-mode arrays of the FlexTable and the
    CondensedState from the body's offset (:func:`body_modes`; units there)."""

    coupling_x: np.ndarray  # S_x of each mode (body frame)
    coupling_y: np.ndarray  # S_y
    coupling_r: np.ndarray  # S_theta
    omega: np.ndarray  # omega_i
    load: np.ndarray  # A_i . F, then omega_i A_i . F
    free: np.ndarray  # f_i
    divisor: np.ndarray  # D_i
    velocity: np.ndarray  # eta_i' at the accepted step
    acceleration: np.ndarray  # eta_i'' at the accepted step
    trial: np.ndarray  # eta_i'' at the end of the step


class FrameMotion(NamedTuple):
    """A body frame's turn and motion (global frame)."""

    cs: float  # cosine of the body's angle
    sn: float  # sine of the body's angle
    ax: float  # acceleration x [m/s^2]
    ay: float  # acceleration y [m/s^2]
    ar: float  # angular acceleration [rad/s^2]
    w: float  # angular velocity [rad/s]
    vx: float  # velocity x [m/s]
    vy: float  # velocity y [m/s]


class FrameChange(NamedTuple):
    """A change of a frame's motion (FrameMotion's ax, ay, ar, w, vx, vy)."""

    dax: float
    day: float
    dar: float
    dw: float
    dvx: float
    dvy: float


@kernel(error_model="numpy", inline="always")
def body_modes(flex, cst, f):
    """The ModeViews of the condensed modes of FlexTable row f (CondensedState ``cst``)."""
    o = flex.condensed_offset[f]
    nq = flex.condensed[f]
    W = flex.condensed_coupling
    return ModeViews(W[3 * o:3 * o + nq], W[3 * o + nq:3 * o + 2 * nq], W[3 * o + 2 * nq:3 * o + 3 * nq],
                     flex.condensed_omega[o:o + nq], cst.load[o:o + nq], cst.free[o:o + nq], cst.divisor[o:o + nq],
                     cst.velocity[o:o + nq], cst.acceleration[o:o + nq], cst.trial[o:o + nq])


@kernel(error_model="numpy", inline="always")
def condensed_coefficients(flex, cst):
    """The step's coefficients of every flexible body's condensed modes (FlexTable rows f) into
    ``cst`` (a CondensedState): ``kappa``, ``divisor`` D_i, ``free`` f_i, ``history`` omega_i
    (x^_i + beta h^2 f_i / D_i) and ``inertia_weight`` S_di kappa_i / ((1 + alpha) omega_i)
    (module docstring). Quasi-static (``cst.mode[0] == STATIC``): kappa_i = 1, no history,
    weights S_di / omega_i. Integrated with ``cst.step[0] == 0``: the modes held at their
    accepted state (kappa_i = 0, history omega_i eta_i), the start of the integrator's call.

    The coefficients that depend on the step, alpha and the condensation alone (kappa, D,
    weights) are computed when these change (``coefficient_key[f, :3]``: a step's Newton
    iterations, and the steps of a run, share them); the free response and the history, which
    depend on the accepted state and the step, once per step (``coefficient_key[f, 3]``: the
    step they were computed for, NaN after the state changed: :func:`accept_condensed`,
    :func:`start_condensed`, :func:`static_condensed`). All bodies in one call: every array of
    a table handed to a compiled function, inlined or not, costs a reference count per call."""
    om = flex.condensed_omega
    cd = flex.condensed_damping
    W = flex.condensed_coupling
    kap = cst.kappa
    hist = cst.history
    iw = cst.inertia_weight
    h = cst.step[0]
    alpha = cst.alpha[0]
    mode = cst.mode[0]
    key = cst.coefficient_key
    pos = cst.position
    vel = cst.velocity
    acc = cst.acceleration
    res = cst.residual
    div = cst.divisor
    free = cst.free
    beta, gamma_ = hht_coefficients(alpha)
    bh2 = beta * h * h
    for f in range(flex.body.shape[0]):
        nq = flex.condensed[f]
        o = flex.condensed_offset[f]
        # the same step up to the round-off of the integrator's t_target - t (about 1e-13 h: the
        # steps of a run are not bit for bit equal), so that a run's steps share the coefficients
        fresh = not (key[f, 0] == mode and abs(key[f, 1] - h) <= STEP_ROUNDOFF * h and key[f, 2] == alpha)
        if mode == STATIC:
            if fresh:
                for i in range(nq):
                    kap[o + i] = 1.0
                    hist[o + i] = 0.0
                    for d in range(3):
                        iw[3 * o + d * nq + i] = W[3 * o + d * nq + i] / om[o + i]
                key[f, 0] = mode
                key[f, 1] = h
                key[f, 2] = alpha
            continue
        if fresh:
            for i in range(nq):
                j = o + i
                w = om[j]
                D = 1.0 + (1.0 + alpha) * (cd[j] * gamma_ * h + w * w * beta * h * h)
                div[j] = D
                k = (1.0 + alpha) * beta * h * h * w * w / D
                kap[j] = k
                for d in range(3):
                    iw[3 * o + d * nq + i] = W[3 * o + d * nq + i] * k / ((1.0 + alpha) * w)
            key[f, 0] = mode
            key[f, 1] = h
            key[f, 2] = alpha
            key[f, 3] = np.nan
        if key[f, 3] == h:  # this step's free response and history: computed at its first evaluation
            continue
        key[f, 3] = h
        # (the body's modes through views indexed by the loop counter alone: contiguous loads)
        ov = om[o:o + nq]
        cdv = cd[o:o + nq]
        pv = pos[o:o + nq]
        vv = vel[o:o + nq]
        av = acc[o:o + nq]
        rv = res[o:o + nq]
        fv = free[o:o + nq]
        hv = hist[o:o + nq]
        dv = div[o:o + nq]
        for i in range(nq):
            w = ov[i]
            c = cdv[i]
            xh = pv[i] + h * vv[i] + (0.5 - beta) * h * h * av[i]
            vh = vv[i] + (1.0 - gamma_) * h * av[i]
            fr = (1.0 + alpha) * (-c * vh - w * w * xh) + alpha * rv[i]
            fv[i] = fr
            hv[i] = w * (xh + bh2 * fr / dv[i])


@kernel(error_model="numpy", inline="always")
def frame_acceleration(Jb, acc, gam, body):
    """Acceleration of the frame of body ``body``, ``J_body q'' + gamma`` (global x, y and
    angle) [m/s^2, rad/s^2], from the pose Jacobians ``Jb``, the accelerations ``acc`` and the
    convective accelerations ``gam`` (:class:`flexgear.dynamics.integrator.buffers.BodyState`)."""
    ax = gam[body, 0]
    ay = gam[body, 1]
    ar = gam[body, 2]
    for c in range(acc.shape[0]):
        ax += Jb[body, 0, c] * acc[c]
        ay += Jb[body, 1, c] * acc[c]
        ar += Jb[body, 2, c] * acc[c]
    return ax, ay, ar


@kernel(error_model="numpy", inline="always")
def frame_moves(Jb, body):
    """Whether a coordinate moves the frame of body ``body``: a row of its pose Jacobian ``Jb``
    (:class:`flexgear.dynamics.integrator.buffers.BodyState`) not zero (a fixed frame or a prescribed rotation: none)."""
    for d in range(3):
        for r in range(Jb.shape[2]):
            if Jb[body, d, r] != 0.0:
                return True
    return False


@kernel(error_model="numpy", inline="always")
def mode_frame_coupling(W, o, nq, i, cs, sn):
    """Coupling of condensed mode ``i`` of the body whose modes start at ``o`` (``nq`` of them)
    with its frame's motion: the mode's x, y coupling (``FlexTable.condensed_coupling``) turned
    into the global frame by the body's angle (cos ``cs``, sin ``sn``), and its rotation
    coupling [sqrt(kg), sqrt(kg) m]."""
    return turned_coupling(W[3 * o + i], W[3 * o + nq + i], W[3 * o + 2 * nq + i], cs, sn)


@kernel(error_model="numpy", inline="always")
def turned_coupling(sx, sy, sr, cs, sn):
    """A condensed mode's frame coupling (sx, sy: body frame; sr: rotation) turned into the
    global frame by the body's angle (cos ``cs``, sin ``sn``): (gx, gy, sr)."""
    return cs * sx - sn * sy, sn * sx + cs * sy, sr


@kernel(error_model="numpy", inline="always")
def mode_inertia_load(gx, gy, sr, ax, ay, ar, w, vx, vy):
    """Inertia load l_i of a condensed mode [N/sqrt(kg)] from its frame's acceleration (``ax``,
    ``ay`` [m/s^2], ``ar`` [rad/s^2]), angular velocity ``w`` [rad/s] and velocity (``vx``,
    ``vy``) [m/s], with the global coupling of :func:`mode_frame_coupling`."""
    return -(gx * ax + gy * ay + sr * ar) + w * (-gx * vy + gy * vx)


# reassociated sums and the divisions by D_i as products with 1 / D_i (vectorised, in an order of
# the compiler's: the last digits differ from plain loops'); a function of its own, so that the
# flags reach this loop only
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract", "arcp"})
def mode_accelerations(nq, modes, frame, alpha, gamma_, h, moving):
    """The end accelerations ``modes.trial`` of a body's nq condensed modes (a ModeViews) and the
    sums over them of :func:`condensed_response`, for its frame's motion ``frame`` (a
    FrameMotion) in a step h with HHT parameter alpha (and gamma): returns the
    turning coupling's (qx, qy) = R S_t eta', and, for a moving frame, the reaction (px, py, pr)
    = R S eta'' and the six entries of ``B = sum_i g_i g_i^T / D_i`` (bxx, bxy, bxr, byy, byr,
    brr; zeros for a frame that does not move). The sums are reassociated and the divisions
    replaced by products with the reciprocal (the compiler vectorises the loop); nothing else
    evaluates them, so no other result has to equal them bit for bit."""
    Wx = modes.coupling_x
    Wy = modes.coupling_y
    Wr = modes.coupling_r
    load = modes.load
    free = modes.free
    div = modes.divisor
    cvel = modes.velocity
    cacc = modes.acceleration
    trial = modes.trial
    cs, sn, ax, ay, ar, w, vx, vy = frame
    a1 = 1.0 + alpha
    # the accelerations, mode by mode (a loop without sums, vectorised), then the sums over the
    # modes (a loop that only reads, vectorised with the reassociated sums)
    for i in range(nq):
        gx, gy, sr = turned_coupling(Wx[i], Wy[i], Wr[i], cs, sn)  # mode_frame_coupling through the views
        trial[i] = (a1 * load[i] + free[i] + mode_inertia_load(gx, gy, sr, ax, ay, ar, w, vx, vy)) / div[i]
    px = 0.0
    py = 0.0
    pr = 0.0
    qx = 0.0
    qy = 0.0
    bxx = 0.0
    bxy = 0.0
    bxr = 0.0
    byy = 0.0
    byr = 0.0
    brr = 0.0
    gh = gamma_ * h
    g1h = (1.0 - gamma_) * h
    if moving:
        for i in range(nq):
            gx, gy, sr = turned_coupling(Wx[i], Wy[i], Wr[i], cs, sn)
            ea = trial[i]
            ev = cvel[i] + g1h * cacc[i] + gh * ea
            qx += gx * ev
            qy += gy * ev
            px += gx * ea
            py += gy * ea
            pr += sr * ea
            rD = 1.0 / div[i]
            bxx += gx * gx * rD
            bxy += gx * gy * rD
            bxr += gx * sr * rD
            byy += gy * gy * rD
            byr += gy * sr * rD
            brr += sr * sr * rD
    else:
        for i in range(nq):
            gx, gy, _ = turned_coupling(Wx[i], Wy[i], Wr[i], cs, sn)
            ev = cvel[i] + g1h * cacc[i] + gh * trial[i]
            qx += gx * ev
            qy += gy * ev
    return qx, qy, px, py, pr, bxx, bxy, bxr, byy, byr, brr


# as mode_accelerations: reassociated sums, divisions as products with the reciprocal
@kernel(error_model="numpy", _nrt=False, fastmath={"reassoc", "contract", "arcp"})
def mode_corrections(nq, modes, dwork, frame, change, alpha, dynamic, moving):
    """The first-order correction of a body's nq condensed modes (a ModeViews) in a one-pass
    step (:func:`flexgear.dynamics.integrator.one_pass.linearised_acceptance`): their load by
    ``dl_i = omega_i dwork_i`` (``dwork``: ``A_i . dF_e``, overwritten), and if ``dynamic``
    (integrated, inside a step) their trial accelerations by ``((1 + alpha) dl_i + dell_i) /
    D_i``, with ``dell_i`` the change of the inertia load when the frame's motion ``frame`` (a
    FrameMotion) changes by ``change`` (a FrameChange; zero for a frame that does not move).
    Returns the change of the modes' reaction on the frame, ``sum_i g_i d eta''_i`` (px, py, pr),
    for a moving frame, else zeros."""
    Wx = modes.coupling_x
    Wy = modes.coupling_y
    Wr = modes.coupling_r
    om = modes.omega
    load = modes.load
    trial = modes.trial
    div = modes.divisor
    cs, sn, ax, ay, ar, w, vx, vy = frame
    dax, day, dar, dw, dvx, dvy = change
    a1 = 1.0 + alpha
    for i in range(nq):
        dl = om[i] * dwork[i]
        load[i] += dl
        dwork[i] = dl
    if not dynamic:
        return 0.0, 0.0, 0.0
    if not moving:  # dell = 0
        for i in range(nq):
            trial[i] += a1 * dwork[i] / div[i]
        return 0.0, 0.0, 0.0
    for i in range(nq):
        gx, gy, sr = turned_coupling(Wx[i], Wy[i], Wr[i], cs, sn)  # mode_frame_coupling through the views
        dell = (mode_inertia_load(gx, gy, sr, ax + dax, ay + day, ar + dar, w + dw, vx + dvx, vy + dvy)
                - mode_inertia_load(gx, gy, sr, ax, ay, ar, w, vx, vy))
        dea = (a1 * dwork[i] + dell) / div[i]
        trial[i] += dea
        dwork[i] = dea
    px = 0.0
    py = 0.0
    pr = 0.0
    for i in range(nq):
        gx, gy, sr = turned_coupling(Wx[i], Wy[i], Wr[i], cs, sn)
        d = dwork[i]
        px += gx * d
        py += gy * d
        pr += sr * d
    return px, py, pr


@kernel(error_model="numpy", inline="always")
def condensed_response(flex, cst, body_flex, contacts, state, system):
    """After the contact solve, for every flexible body (in body order; FlexTable row f =
    ``body_flex[body]``): the generalised contact force ``load`` = A_i . F of its condensed
    modes; integrated (and ``cst.step[0] > 0``) also their end accelerations
    ``trial`` and their reaction on the frame: the inertia force ``J^T R S eta''`` into
    ``inertia_load``, its derivative through the frame's acceleration, ``-J^T R (sum_i S_i
    S_i^T / D_i) R^T J`` (in the Newton matrix, not in the residual's ``Mq a``: the reaction
    already holds it), into the tangent ``Kt`` divided by the step's (1 + alpha) beta h^2, and
    the turning coupling's force and torque
    of the modes' velocity (:mod:`flexgear.dynamics.flexible.floating_frame`) into the body loads ``Fb``. (Its derivative
    through the contact forces goes into the tangent with the contact rows:
    :func:`flexgear.dynamics.flexible.compliant.compliant_contacts`.) All bodies in one call (see
    :func:`condensed_coefficients`). Reads the contacts' modal rows ``flank_modes``, slots and
    elastic forces (ContactBuffers ``contacts``) and the bodies' kinematics (BodyState ``state``);
    writes ``system.inertia_load``, ``system.stiffness`` and ``state.load``.
    """
    flank_modes = contacts.flank_modes
    body_slot = contacts.body_slot
    body_count = contacts.body_count
    Fe = contacts.elastic_force
    pose = state.pose
    acc = state.accelerations
    gam = state.convective
    vel = state.vel
    Jb = state.jacobian
    Fb = state.load
    inertia_load = system.inertia_load
    Kt = system.stiffness
    om = flex.condensed_omega
    load = cst.load
    h = cst.step[0]
    static = cst.mode[0] == STATIC or h == 0.0
    alpha = cst.alpha[0]
    beta, gamma_ = hht_coefficients(alpha)
    for body in range(body_flex.shape[0]):
        f = body_flex[body]
        if f < 0:
            continue
        nk = body_count[f]
        ax, ay, ar = frame_acceleration(Jb, acc, gam, body)
        cs = math.cos(pose[body, 2])
        sn = math.sin(pose[body, 2])
        nq = flex.condensed[f]
        o = flex.condensed_offset[f]
        # the body's modes as views indexed by the loop counter alone (contiguous vector loads
        # and stores; an index o + i could be negative for the compiler, which then checks it)
        lv = load[o:o + nq]
        # A_i . F contact by contact (rows of flank_modes contiguous; each mode's sum in contact
        # order, as one mode at a time would; an open contact adds nothing)
        for i in range(nq):
            lv[i] = 0.0
        for k in range(nk):
            fk = Fe[body_slot[f, k]]
            if fk == 0.0:
                continue
            Uk = flank_modes[f, k]
            for i in range(nq):
                lv[i] += Uk[i] * fk
        ov = om[o:o + nq]
        for i in range(nq):
            lv[i] *= ov[i]
        if static:
            continue
        w = vel[body, 2]
        # the reaction and its derivative reach only the coordinates that move the frame: a
        # frame no coordinate moves (fixed, or a prescribed rotation: its Jacobian rows all
        # zero) needs only the accelerations and the turning coupling (MERCURY 1-A: the ring,
        # 163 of 358 modes, 6 divisions each)
        moving = frame_moves(Jb, body)
        qx, qy, px, py, pr, bxx, bxy, bxr, byy, byr, brr = mode_accelerations(
            nq, body_modes(flex, cst, f), FrameMotion(cs, sn, ax, ay, ar, w, vel[body, 0], vel[body, 1]), alpha, gamma_,
            h, moving)
        n = inertia_load.shape[0]
        sc = 1.0 / ((1.0 + alpha) * beta * h * h)
        for r in range(n if moving else 0):
            j0 = Jb[body, 0, r]
            j1 = Jb[body, 1, r]
            j2 = Jb[body, 2, r]
            if j0 == 0.0 and j1 == 0.0 and j2 == 0.0:
                continue
            inertia_load[r] += j0 * px + j1 * py + j2 * pr
            # row r of J^T B: B = sum_i g_i g_i^T / D_i (symmetric)
            ux = sc * (j0 * bxx + j1 * bxy + j2 * bxr)
            uy = sc * (j0 * bxy + j1 * byy + j2 * byr)
            ur = sc * (j0 * bxr + j1 * byr + j2 * brr)
            for s in range(n):
                Kt[r, s] -= ux * Jb[body, 0, s] + uy * Jb[body, 1, s] + ur * Jb[body, 2, s]
        # p = R S_t eta' (global): force -w E p, torque r_c'^T E p on the frame
        Fb[body, 0] += w * qy
        Fb[body, 1] -= w * qx
        Fb[body, 2] += -vel[body, 0] * qy + vel[body, 1] * qx


@kernel(error_model="numpy", _nrt=False)
def accept_condensed(flex, cst, h):
    """Advance every condensed mode to the end of an accepted step h: eta, eta', eta'' from the
    last evaluation's ``trial`` acceleration (Newmark), and the residual P = c eta' + omega^2
    eta - A . F that the next step weights by alpha. Returns False if a mode's state is not
    finite."""
    for j in range(cst.trial.shape[0]):
        if not math.isfinite(cst.trial[j]):
            return False
    beta, gamma_ = hht_coefficients(cst.alpha[0])
    # in place: each mode's new eta, eta' read only its own old eta, eta', eta''
    predict(cst.position, cst.velocity, cst.acceleration, cst.trial, h, beta, gamma_, cst.position, cst.velocity)
    for j in range(cst.trial.shape[0]):  # element by element: a slice copy may allocate (no NRT here)
        cst.acceleration[j] = cst.trial[j]
    stale_history(cst)
    om = flex.condensed_omega
    cd = flex.condensed_damping
    for j in range(cst.position.shape[0]):
        cst.residual[j] = cd[j] * cst.velocity[j] + om[j] * om[j] * cst.position[j] - cst.load[j]
    return True


@kernel(error_model="numpy")
def static_condensed(flex, cst):
    """Set every condensed mode to its static response to the last evaluation's contact forces,
    eta_i = A_i . F / omega_i^2, at rest: the start of a run (a gear set loaded at its start, a
    free vibration about a static equilibrium, starts in equilibrium; from rest, eta = 0)."""
    om = flex.condensed_omega
    for j in range(cst.position.shape[0]):
        cst.position[j] = cst.load[j] / (om[j] * om[j])
        cst.velocity[j] = 0.0
        cst.acceleration[j] = 0.0
    cst.started[0] = 1
    stale_history(cst)


@kernel(error_model="numpy")
def start_condensed(flex, cst):
    """The residual P of the accepted state from the last evaluation's contact forces (an
    evaluation with ``cst.step[0] == 0``: the modes at their accepted state), at the start of
    an integrator call."""
    om = flex.condensed_omega
    cd = flex.condensed_damping
    for j in range(cst.position.shape[0]):
        cst.residual[j] = cd[j] * cst.velocity[j] + om[j] * om[j] * cst.position[j] - cst.load[j]
    stale_history(cst)


@kernel(error_model="numpy")
def stale_history(cst):
    """Mark every body's free response and history (:func:`condensed_coefficients`) as stale:
    the accepted state changed."""
    key = cst.coefficient_key
    for f in range(key.shape[0]):
        key[f, 3] = np.nan
