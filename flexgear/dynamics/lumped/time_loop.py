"""The lumped model in the time domain: HHT-alpha on the piecewise-linear mesh forces, compiled,
with records in the rigid solver's layout (so runs, results, signals, plots and studies work
unchanged).
"""
from __future__ import annotations

import math
import time as _time
from typing import NamedTuple

import numpy as np

from ...kernels import kernel
from ..contact.solve import lu_factor, lu_solve
from ..integrator.simulation import Integration
from ..model.bodies import ANGLE_SPRING, BEARING, MAXC, Profile
from .friction import (MAX_PAIRS, FrictionWork, film_meshes, film_table, friction_forces, friction_records,
                       friction_records_for, kernel_table, linearised_film, linearised_friction, mesh_tangent,
                       place_pairs, record_film, record_lumped_friction)
from .faults import check_carried
from .model import LumpedModel

#: The friction time loop's ``linear_tol``: the largest step of a pair's sliding speed (relative
#: to max(|v_s|, v_0)) or load (relative) from the point its friction was linearised about that
#: a step accepts (the linearisation's relative error is about its square); beyond it the step
#: is linearised again about its solution.
FRICTION_TOL = 0.1


class LumpedSystem(NamedTuple):
    """The lumped model's linear part in its coordinates q (deviations from the nominal motion)."""

    mass: np.ndarray  # (n, n) float: M
    stiffness: np.ndarray  # (n, n) float: every spring but the meshes (bearings, supports, shafts)
    damping: np.ndarray  # (n, n) float: their damping
    mesh_gradient: np.ndarray  # (nm, n) float: G, mesh deflection along the line of action per coordinate
    backlash: np.ndarray  # (nm,) float: backlash along the line of action [m]


class MeshCycle(NamedTuple):
    """Each mesh's stiffness, offset and damping at P positions per table period (one mesh cycle;
    with faults or errors ``LumpedModel.cycles`` of them)."""

    stiffness: np.ndarray  # (nm, P) float [N/m]
    offset: np.ndarray  # (nm, P) float: e(phi) [m]
    damping: np.ndarray  # (nm, P) float [N s/m]


class LumpedLoad(NamedTuple):
    """What drives the lumped model, at every step time of the run."""

    phase: np.ndarray  # (steps + 1,) float: position phi in table periods (mesh cycles when healthy)
    force: np.ndarray  # (steps + 1, n) float: external generalised force


class LumpedSettings(NamedTuple):
    """Step, HHT parameter and contact-state iterations of the lumped time loop."""

    h: float  # step [s]
    alpha: float  # HHT parameter [-]
    max_newton: int  # contact-state iterations per step


class LumpedRecords(NamedTuple):
    """The lumped time loop's records, one row per step."""

    q: np.ndarray  # (steps, n) float: coordinates
    v: np.ndarray  # (steps, n) float: velocities
    force: np.ndarray  # (steps, nm) float: mesh forces [N]
    deflection: np.ndarray  # (steps, nm) float: mesh deflections beyond the offset [m]


# the per-step helpers take tables and create no arrays: compiled without reference counting, so
# that taking the tables' arrays apart costs nothing (with it, an atomic increment and decrement
# each, every step)
@kernel(fastmath=True, error_model="numpy", _nrt=False)
def _tables_at(cycle, phi, kk, ee, cc):
    """Mesh stiffness, offset and damping of every mesh at the mesh-cycle position phi (periodic,
    linear between the P tabulated positions of ``cycle``, a MeshCycle)."""
    ktab = cycle.stiffness
    etab = cycle.offset
    ctab = cycle.damping
    P = ktab.shape[1]
    x = phi * P
    f = math.floor(x)
    w = x - f
    i = int(f) % P
    j = (i + 1) % P
    for m in range(ktab.shape[0]):
        kk[m] = (1.0 - w) * ktab[m, i] + w * ktab[m, j]
        ee[m] = (1.0 - w) * etab[m, i] + w * etab[m, j]
        cc[m] = (1.0 - w) * ctab[m, i] + w * ctab[m, j]


@kernel(fastmath=True, _nrt=False, inline="always")
def _contact(k, e, c, backlash, d, dd):
    """Force [N] and contact state (1 drive flank, -1 back flank, 0 open) of a mesh of stiffness
    k, offset e, damping c and backlash at deflection d [m] and rate dd [m/s]: a flank in contact
    pushes, never pulls (a clipped force is an open mesh)."""
    if d > e:
        f = k * (d - e) + c * dd
        if f > 0.0:
            return f, 1
    elif d < -e - backlash:
        f = k * (d + e + backlash) + c * dd
        if f < 0.0:
            return f, -1
    return 0.0, 0


@kernel(fastmath=True, error_model="numpy", _nrt=False)
def _mesh_state(q, v, system, kk, ee, cc, fint, F, defl, active):
    """Mesh forces F, contact states (1 drive flank, -1 back flank, 0 open) and deflections
    beyond the offset for the mesh stiffness kk, offset ee and damping cc, and the internal
    force fint = Kb q + Cb v + sum F_m G_m (``system``, a LumpedSystem)."""
    G = system.mesh_gradient
    Kb = system.stiffness
    Cb = system.damping
    backlash = system.backlash
    n = q.shape[0]
    nm = G.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Kb[i, j] * q[j] + Cb[i, j] * v[j]
        fint[i] = s
    for m in range(nm):
        d = 0.0
        dd = 0.0
        for j in range(n):
            d += G[m, j] * q[j]
            dd += G[m, j] * v[j]
        f, act = _contact(kk[m], ee[m], cc[m], backlash[m], d, dd)
        F[m] = f
        defl[m] = d - ee[m]
        active[m] = act
        if f != 0.0:
            for i in range(n):
                fint[i] += f * G[m, i]


@kernel(fastmath=True)
def _solve_spd(A, b, x):
    """Solve A x = b for symmetric positive definite A (Cholesky, in place on A)."""
    n = A.shape[0]
    for j in range(n):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        d = math.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= A[i, k] * x[k]
        x[i] = s / A[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= A[k, i] * x[k]
        x[i] = s / A[i, i]


@kernel(fastmath=True)
def integrate_lumped(q, v, a, k0, nsteps, system, cycle, load, settings, records, stats):
    """Advance (q, v, a) by nsteps steps of ``settings.h`` from step index k0 (HHT-alpha) of the
    LumpedSystem ``system`` with the meshes' MeshCycle ``cycle``, driven by ``load`` (a
    LumpedLoad over the whole run), into ``records`` (a LumpedRecords window of nsteps rows).

    The forces are linear for a given contact state of the meshes, so each iteration solves the
    step exactly for the assumed states (taken from the previous step) and checks them at the
    new state; a change repeats the step with the new states (up to ``settings.max_newton``
    times). stats: [steps, iterations, max iterations in a step, steps whose contact states kept
    changing]."""
    M = system.mass
    Kb = system.stiffness
    Cb = system.damping
    G = system.mesh_gradient
    backlash = system.backlash
    phi = load.phase
    fext = load.force
    h, alpha, max_newton = settings
    rec_q = records.q
    rec_v = records.v
    rec_F = records.force
    rec_d = records.deflection
    n = q.shape[0]
    nm = G.shape[0]
    beta = 0.25 * (1.0 - alpha) ** 2
    gam = 0.5 - alpha
    fint = np.zeros(n)
    fint_n = np.zeros(n)
    A = np.zeros((n, n))
    Kt = np.zeros((n, n))
    Ct = np.zeros((n, n))
    b = np.zeros(n)
    an = np.zeros(n)
    qp = np.zeros(n)
    vp = np.zeros(n)
    qq = np.zeros(n)
    vv = np.zeros(n)
    F = np.zeros(nm)
    defl = np.zeros(nm)
    act = np.zeros(nm, np.int64)
    new = np.zeros(nm, np.int64)
    kk = np.zeros(nm)
    ee = np.zeros(nm)
    cc = np.zeros(nm)
    _tables_at(cycle, phi[k0], kk, ee, cc)
    _mesh_state(q, v, system, kk, ee, cc, fint_n, F, defl, act)
    c1 = 1.0 + alpha
    for s in range(nsteps):
        k = k0 + s
        _tables_at(cycle, phi[k + 1], kk, ee, cc)
        for i in range(n):
            qp[i] = q[i] + h * v[i] + h * h * (0.5 - beta) * a[i]
            vp[i] = v[i] + h * (1.0 - gam) * a[i]
        it = 0
        settled = False
        while it < max_newton:
            it += 1
            # tangent and constant term of the forces for the assumed contact states
            for i in range(n):
                for j in range(n):
                    Kt[i, j] = Kb[i, j]
                    Ct[i, j] = Cb[i, j]
                b[i] = c1 * fext[k + 1, i] - alpha * (fext[k, i] - fint_n[i])
            for m in range(nm):
                if act[m] == 0:
                    continue
                km = kk[m]
                cm = cc[m]
                off = ee[m]
                if act[m] < 0:
                    off = -off - backlash[m]
                for i in range(n):
                    gi = G[m, i]
                    if gi == 0.0:
                        continue
                    b[i] += c1 * km * off * gi
                    for j in range(n):
                        Kt[i, j] += km * gi * G[m, j]
                        Ct[i, j] += cm * gi * G[m, j]
            for i in range(n):
                s1 = 0.0
                for j in range(n):
                    s1 += Kt[i, j] * qp[j] + Ct[i, j] * vp[j]
                    A[i, j] = M[i, j] + c1 * (beta * h * h * Kt[i, j] + gam * h * Ct[i, j])
                b[i] -= c1 * s1
            _solve_spd(A, b, an)
            for i in range(n):
                qq[i] = qp[i] + beta * h * h * an[i]
                vv[i] = vp[i] + gam * h * an[i]
            _mesh_state(qq, vv, system, kk, ee, cc, fint, F, defl, new)
            settled = True
            for m in range(nm):
                if new[m] != act[m]:
                    settled = False
                act[m] = new[m]
            if settled:
                break
        stats[1] += it
        if it > stats[2]:
            stats[2] = it
        if not settled:
            stats[3] += 1
        for i in range(n):
            q[i] = qq[i]
            v[i] = vv[i]
            a[i] = an[i]
            fint_n[i] = fint[i]
            rec_q[s, i] = qq[i]
            rec_v[s, i] = vv[i]
        for j in range(nm):
            rec_F[s, j] = F[j]
            rec_d[s, j] = defl[j]
        stats[0] += 1
    return 0


@kernel(fastmath=True, _nrt=False, inline="always")
def _assumed_forces(q, v, system, kk, ee, cc, act, fint, F, defl, new):
    """Internal force fint = Kb q + Cb v + sum F_m G_m with each mesh's force F_m for its assumed
    contact state ``act`` (1 drive flank, -1 back flank, 0 open: affine in q, v, not clipped),
    and at the same q, v the states ``new`` and deflections ``defl`` :func:`_mesh_state` finds."""
    G = system.mesh_gradient
    Kb = system.stiffness
    Cb = system.damping
    backlash = system.backlash
    n = q.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Kb[i, j] * q[j] + Cb[i, j] * v[j]
        fint[i] = s
    for m in range(G.shape[0]):
        d = 0.0
        dd = 0.0
        for j in range(n):
            d += G[m, j] * q[j]
            dd += G[m, j] * v[j]
        new[m] = _contact(kk[m], ee[m], cc[m], backlash[m], d, dd)[1]
        defl[m] = d - ee[m]
        F[m] = 0.0
        if act[m] == 0:
            continue
        off = ee[m] if act[m] > 0 else -ee[m] - backlash[m]
        f = kk[m] * (d - off) + cc[m] * dd
        F[m] = f
        for i in range(n):
            fint[i] += f * G[m, i]


class FrictionState(NamedTuple):
    """The friction time loop's state and working arrays (:func:`friction_state`), kept from one
    window of steps to the next: the coordinates, velocities and accelerations, the internal
    force and contact states of the last step, the step's vectors and iteration matrix, the mesh
    tables at the step and the pairs (``work``)."""

    q: np.ndarray  # (n,) coordinates (updated in place)
    v: np.ndarray  # (n,) velocities
    a: np.ndarray  # (n,) accelerations
    fint_n: np.ndarray  # (n,) internal force of the last step (HHT's alpha term)
    act: np.ndarray  # (nm,) int: contact states of the last step
    fint: np.ndarray  # (n,)
    A: np.ndarray  # (n, n) iteration matrix (LU in place)
    piv: np.ndarray  # (n,) int
    r: np.ndarray  # (n,)
    b0: np.ndarray  # (n,)
    dv: np.ndarray  # (n,)
    an: np.ndarray  # (n,)
    qp: np.ndarray  # (n,)
    vp: np.ndarray  # (n,)
    qq: np.ndarray  # (n,)
    vv: np.ndarray  # (n,)
    F: np.ndarray  # (nm,)
    defl: np.ndarray  # (nm,)
    new: np.ndarray  # (nm,) int
    kk: np.ndarray  # (nm,)
    ee: np.ndarray  # (nm,)
    cc: np.ndarray  # (nm,)
    work: FrictionWork
    stats: np.ndarray  # (4,) int: the loop's counts (integrate_lumped_friction)


def friction_state(q: np.ndarray, v: np.ndarray, a: np.ndarray, nm: int, stats: np.ndarray) -> FrictionState:
    """The :class:`FrictionState` of the motion (q, v, a) (the arrays themselves, advanced in
    place) and nm meshes, zeroed, counting into ``stats``."""
    n = q.shape[0]
    z = np.zeros
    work = FrictionWork(z(nm, np.int64), *(z((nm, MAX_PAIRS)) for _ in range(4)), z(nm),
                        *(z((nm, MAX_PAIRS)) for _ in range(4)))
    return FrictionState(q, v, a, z(n), z(nm, np.int64), z(n), z((n, n)), z(n, np.int64), *(z(n) for _ in range(8)),
                         z(nm), z(nm), z(nm, np.int64), z(nm), z(nm), z(nm), work, stats)


@kernel(fastmath=True, error_model="numpy", _nrt=False)
def integrate_lumped_friction(k0, nsteps, system, cycle, load, settings, friction, film, state, records):
    """:func:`~flexgear.dynamics.lumped.time_loop.integrate_lumped` with tooth friction
    (``friction``, a MeshFriction; ``state`` a FrictionState with the motion (q, v, a), set up at
    k0 = 0 and carried between windows; ``records`` FrictionRecords), linearly implicit: the normal mesh forces
    stay exact (affine for the assumed contact states), the friction is linearised about the
    HHT predictor (q_n + h v_n + h^2/2 a_n, v_n + h a_n: O(h^2) from the step's solution) with its
    exact tangent there (:func:`~flexgear.dynamics.lumped.friction.mesh_tangent`), and
    the step is one linear solve (LU: the tangent is not symmetric) with one evaluation of the
    friction law. Where a pair's sliding speed or load moves further from the linearisation
    point than ``friction.linear_tol`` of the scale its coefficient curves on
    (:func:`~flexgear.dynamics.lumped.friction.linearised_friction`: near the sign change at the
    pitch point when the mesh vibrates) the step is linearised again about its solution (a
    Newton iteration). As in the frictionless loop, each iteration takes the meshes' contact
    states from the previous one and checks them at the solution; a change (or a mesh in
    contact that carried no friction at the linearisation point) repeats the step the same way,
    up to ``settings.max_newton`` solves. ``film``: the squeeze films (a FilmTable; of length 0
    without films, :func:`~flexgear.dynamics.lumped.friction.film_table`); their damping is taken
    at the linearisation point, with its load slope in the tangent, and carried to the solution
    along it (:func:`~flexgear.dynamics.lumped.friction.film_meshes`, ``linearised_film``); a step whose
    elastic mesh force moved further than ``linear_tol`` from there is linearised again.
    state.stats: [steps, linear solves, max solves in a step, steps left unsettled]."""
    M = system.mass
    Kb = system.stiffness
    Cb = system.damping
    G = system.mesh_gradient
    phi = load.phase
    fext = load.force
    h, alpha, max_newton = settings
    q = state.q
    v = state.v
    a = state.a
    fint = state.fint
    fint_n = state.fint_n
    A = state.A
    piv = state.piv
    r = state.r
    b0 = state.b0
    dv = state.dv
    an = state.an
    qp = state.qp
    vp = state.vp
    qq = state.qq
    vv = state.vv
    F = state.F
    defl = state.defl
    act = state.act
    new = state.new
    kk = state.kk
    ee = state.ee
    cc = state.cc
    work = state.work
    stats = state.stats
    n = q.shape[0]
    nm = G.shape[0]
    films = film.factor.shape[0] > 0  # squeeze films (one compiled loop: a run without takes an empty table)
    if films:  # the mesh damping and tangent stiffness: the films', or the tables'
        damp = film.damp
        kt = film.kt
    else:
        damp = cc
        kt = kk
    beta = 0.25 * (1.0 - alpha) ** 2
    gam = 0.5 - alpha
    c1 = 1.0 + alpha
    sq = c1 * beta * h * h
    sv = c1 * gam * h
    tol = friction.linear_tol
    out_every = friction.out_every
    to_sample = out_every  # steps to the next output sample (a window starts at one)
    samples = 0
    if k0 == 0:
        _tables_at(cycle, phi[0], kk, ee, cc)
        place_pairs(friction, phi[0], friction.speed[0], work)
        if films:
            film_meshes(friction, film, system, q, v, kk, ee, cc, act, friction.speed[0], work)
        _mesh_state(q, v, system, kk, ee, damp, fint_n, F, defl, act)
        friction_forces(friction, v, F, fint_n, work)
    for s in range(nsteps):
        k = k0 + s
        _tables_at(cycle, phi[k + 1], kk, ee, cc)
        place_pairs(friction, phi[k + 1], friction.speed[k + 1], work)
        for i in range(n):
            qp[i] = q[i] + h * v[i] + h * h * (0.5 - beta) * a[i]
            vp[i] = v[i] + h * (1.0 - gam) * a[i]
            b0[i] = c1 * fext[k + 1, i] - alpha * (fext[k, i] - fint_n[i])
            an[i] = a[i]
        it = 0
        settled = False
        while it < max_newton:
            it += 1
            # the forces, the friction and its tangent at the linearisation point
            for i in range(n):
                qq[i] = qp[i] + beta * h * h * an[i]
                vv[i] = vp[i] + gam * h * an[i]
            if films:
                film_meshes(friction, film, system, qq, vv, kk, ee, cc, act, friction.speed[k + 1], work)
            _assumed_forces(qq, vv, system, kk, ee, damp, act, fint, F, defl, new)
            friction_forces(friction, vv, F, fint, work)
            for i in range(n):
                s1 = 0.0
                for j in range(n):
                    s1 += M[i, j] * an[j]
                    A[i, j] = M[i, j] + sq * Kb[i, j] + sv * Cb[i, j]
                r[i] = b0[i] - s1 - c1 * fint[i]
            mesh_tangent(friction, system, kt, damp, act, sq, sv, work, A)
            if not lu_factor(A, piv, n):
                break  # singular: the step is left unsettled
            lu_solve(A, piv, r, n)
            # the solution, its forces and the friction carried to it along the tangent
            for i in range(n):
                an[i] += r[i]
                dv[i] = gam * h * r[i]
                qq[i] = qp[i] + beta * h * h * an[i]
                vv[i] = vp[i] + gam * h * an[i]
            _assumed_forces(qq, vv, system, kk, ee, damp, act, fint, F, defl, new)
            film_within = True
            if films:
                film_within = linearised_film(film, system, vv, kk, defl, act, F, fint, tol)
            settled = linearised_friction(friction, dv, F, fint, work, tol) and film_within
            for m in range(nm):
                if new[m] != act[m] or (new[m] > 0 and work.count[m] > 0 and work.load[m] <= 0.0):
                    settled = False
                act[m] = new[m]
            if settled:
                break
        if not settled:  # the forces of the last solution, with its actual contact states
            for i in range(n):
                qq[i] = qp[i] + beta * h * h * an[i]
                vv[i] = vp[i] + gam * h * an[i]
            _mesh_state(qq, vv, system, kk, ee, damp, fint, F, defl, act)
            friction_forces(friction, vv, F, fint, work)
        stats[1] += it
        stats[2] = max(stats[2], it)
        if not settled:
            stats[3] += 1
        for i in range(n):
            q[i] = qq[i]
            v[i] = vv[i]
            a[i] = an[i]
            fint_n[i] = fint[i]
            records.q[s, i] = qq[i]
            records.v[s, i] = vv[i]
        for m in range(nm):
            records.force[s, m] = F[m]
            records.deflection[s, m] = defl[m]
        to_sample -= 1
        js = -1
        if to_sample == 0:
            js = samples
            samples += 1
            to_sample = out_every
        record_lumped_friction(friction, k + 1, s, js, F, work, records)
        if films:
            record_film(film, system, s, js, vv, kk, F, defl, records)
        stats[0] += 1
    return 0


def _drive_angle(profile: Profile, t: np.ndarray):
    """Angle turned since t = 0 [rad], speed [rad/s] and acceleration [rad/s^2] of a speed profile."""
    w = profile(t)
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    acc = np.gradient(w, t) if len(t) > 1 else np.zeros_like(t)
    return ang, w, acc


def _ramp(t, ramp):
    if ramp <= 0:
        return np.ones_like(t)
    x = np.clip(t / ramp, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def simulate_lumped(lm: LumpedModel, t_end: float, h: float, out_every: int, alpha: float = -0.1,
                    max_newton: int = 12, progress=None, chunk_steps: int = 20000,
                    friction_tol: float = FRICTION_TOL) -> Integration:
    """Integrate the lumped model from 0 to t_end; records in the rigid solver's layout.

    Parameters
    ----------
    t_end, h : float
        End time and step [s] (t_end / h steps, a multiple of out_every).
    out_every : int
        Steps per output sample (tooth-pair slots are sampled there).
    alpha : float
        HHT-alpha parameter in [-1/3, 0].
    max_newton : int
        Linear solves per step (contact-state iterations; with friction also re-linearisations).
    progress : callable(fraction) or None
    friction_tol : float
        With friction: how far (relative) a pair's sliding speed or load may move from where the
        step linearised its friction (:data:`FRICTION_TOL`; a tiny value iterates Newton to the
        implicit solution of the step).
    """
    check_carried(lm)
    model, sysl = lm.model, lm.system
    n = sysl.n
    nm = len(model.meshes)
    nsteps = int(round(t_end / h))
    nsteps -= nsteps % out_every
    t = np.arange(nsteps + 1) * h
    drive = model.bodies[lm.drive]
    ang, w, acc = _drive_angle(drive.speed, t)
    phi = ang / lm.mesh_angle
    if lm.cycles != 1:  # tables over several mesh cycles (faults, errors): phi in table periods
        phi = phi / lm.cycles
    # external forces: applied torques (ramped) and the inertia of the nominal acceleration
    M = sysl.M
    fext = np.zeros((nsteps + 1, n))
    for i, b in enumerate(model.bodies):
        if b.torque is not None and i != lm.drive:
            T = b.torque(t) * _ramp(t, b.torque_ramp)
            fext += np.outer(T, sysl.bodies[b.name][2][2])
    Kb = np.zeros((n, n))
    Cb = np.zeros((n, n))
    for s in sysl.springs:
        if s.kind != "mesh":
            Kb += s.k * np.outer(s.g, s.g)
    for i, b in enumerate(model.bodies):  # bearing and support damping
        if b.name in sysl.bodies and (b.joint == BEARING or b.rotation == ANGLE_SPRING):
            J = sysl.bodies[b.name][2]
            Cb += b.damping * (J[:2].T @ J[:2]) + b.torsional_damping * np.outer(J[2], J[2])
    q = np.zeros(n)
    v = np.zeros(n)
    a = np.zeros(n)
    G = np.ascontiguousarray(lm.G)
    rec_q = np.zeros((nsteps, n))
    rec_v = np.zeros((nsteps, n))
    rec_F = np.zeros((nsteps, nm))
    rec_d = np.zeros((nsteps, nm))
    stats = np.zeros(4, np.int64)
    system = LumpedSystem(M, Kb, Cb, G, lm.backlash)
    cycle = MeshCycle(lm.k, lm.e, lm.c)
    load = LumpedLoad(phi, fext)
    settings = LumpedSettings(float(h), float(alpha), int(max_newton))
    records = LumpedRecords(rec_q, rec_v, rec_F, rec_d)
    step = integrate_lumped
    head = (q, v, a)  # the arguments before the step window
    tail = (stats,)  # the arguments after the records' window
    extra = ()
    films = False  # squeeze films on some mesh (the friction loop's film table not empty)
    if lm.friction is not None:  # tooth friction: its own time loop (the frictionless one stays as it is)
        step = integrate_lumped_friction
        film = film_table(lm.friction)
        films = film.factor.size > 0
        extra = (kernel_table(lm.friction, w, out_every, friction_tol), film, friction_state(q, v, a, nm, stats))
        head = tail = ()
        records = friction_records_for(nsteps, out_every, nm, records, film=films)
    # compile (or load the disk cache) apart from the timing, microseconds once compiled
    t0 = _time.perf_counter()
    step(*(x.copy() for x in head), 0, 0, system, cycle, load, settings, *extra,
         _window(records, 0, 0, out_every), *tail)  # no steps: the counts stay 0, q, v, a unchanged
    compile_seconds = _time.perf_counter() - t0
    wall0 = _time.perf_counter()
    done = 0
    chunk = max(out_every, (chunk_steps // out_every) * out_every)
    while done < nsteps:
        k = min(chunk, nsteps - done)
        step(*head, done, k, system, cycle, load, settings, *extra, _window(records, done, k, out_every), *tail)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            from ...errors import DivergenceError

            bad = ~(np.all(np.isfinite(rec_q[done:done + k]), axis=1) & np.all(np.isfinite(rec_F[done:done + k]), axis=1))
            i = int(np.argmax(bad)) if bad.any() else k - 1
            last = np.nan_to_num(rec_F[done + i - 1]) if done + i > 0 else np.zeros(nm)
            worst = model.meshes[int(np.argmax(np.abs(last)))].name if nm else "-"
            raise DivergenceError(f"lumped simulation diverged: non-finite state at t = {(done + i + 1) * h:.6f} s, "
                                  f"mesh {worst!r} carrying the largest force the step before "
                                  f"({np.max(np.abs(last)) if nm else 0.0:.3g} N). A contact damping far above "
                                  "critical with contact loss can do this (the lumped mesh takes [contact] C as a "
                                  "constant viscous damper: the presets' ADAMS value is many times critical "
                                  "there): give [contact] damping_ratio (e.g. 0.05) instead of C, or lower the step")
        done += k
        if progress is not None:
            progress(done / nsteps)
    wall = _time.perf_counter() - wall0
    tt = t[1:]
    tangential = records.friction if lm.friction is not None and lm.friction.rubs else None
    body, mesh = _records(lm, tt, ang[1:], w[1:], acc[1:], rec_q, rec_v, rec_F, tangential)
    friction = damping = None
    if lm.friction is not None and lm.friction.rubs:
        friction = friction_records(lm, records, body)
    if films:  # the squeeze films: slot 0 holds the mesh
        damping = {"power": records.damping_power, "pair_force": np.zeros((nsteps // out_every, nm, MAXC))}
        damping["pair_force"][:, :, 0] = records.damping_force
    nout = nsteps // out_every
    pair_f = np.zeros((nout, nm, MAXC, 2))
    pair_i = np.full((nout, nm, MAXC, 3), -1, np.int64)
    pair_i[:, :, :, 2] = 0
    sel = slice(out_every - 1, nsteps, out_every)
    Fo, do = rec_F[sel], rec_d[sel]
    pair_f[:, :, 0, 0] = np.abs(Fo)
    pair_f[:, :, 0, 1] = np.where(Fo != 0.0, np.abs(do), 0.0)
    on = Fo != 0.0
    pair_i[:, :, 0, 0] = np.where(on, 0, -1)
    pair_i[:, :, 0, 1] = np.where(on, 0, -1)
    pair_i[:, :, 0, 2] = np.where(Fo > 0, 1, np.where(Fo < 0, -1, 0))
    return Integration(h=h, nsteps=nsteps, out_every=out_every, mesh=mesh, body=body, pair_f=pair_f, pair_i=pair_i,
                       steps=int(stats[0]), newton=int(stats[1]), rejected=int(stats[3]), max_iter=int(stats[2]),
                       wall=wall, q=q, v=v, lumped=True, compile_seconds=compile_seconds, friction=friction,
                       damping=damping)


def _window(records, start: int, k: int, out_every: int):
    """The rows of steps start ... start + k of ``records``: of the arrays with a row per step and
    of those with a row per output sample (start and k multiples of out_every; with out_every = 1
    both slices are the same)."""
    ns = records.q.shape[0]
    return type(records)(*[r[start:start + k] if r.shape[0] == ns else r[start // out_every:(start + k) // out_every]
                           for r in records])


def _records(lm: LumpedModel, t, ang, w, acc, rec_q, rec_v, rec_F, tangential=None):
    """Per-step body poses (x, y, theta, vx, vy, omega, torque) and mesh totals (F, Fx, Fy on b)
    in the global frame: nominal motion plus the deviations; with ``tangential`` (steps, nm) the
    meshes' friction [N] along the flank tangent tau = (-n_y, n_x) (the normal turned by 90
    degrees, :func:`~flexgear.dynamics.lumped.friction.build_friction`) is in Fx, Fy too."""
    model, sysl = lm.model, lm.system
    nb_ = len(model.bodies)
    ns = len(t)
    body = np.zeros((ns, nb_, 7))
    # nominal angles and rates: theta0 + ratio * drive angle
    q0, v0 = model.initial_state()
    names = model.coordinate_names()
    w0 = model.bodies[lm.drive].omega0
    theta = np.zeros((ns, nb_))
    omega = np.zeros((ns, nb_))
    for i, b in enumerate(model.bodies):
        nm_ = f"{b.name}.theta"
        if i == lm.drive:
            theta[:, i] = b.theta0 + ang
            omega[:, i] = w
        elif nm_ in names:
            r = v0[names.index(nm_)] / w0 if w0 != 0 else 0.0
            theta[:, i] = q0[names.index(nm_)] + r * ang
            omega[:, i] = r * w
        else:
            theta[:, i] = b.theta0
        if b.name in sysl.bodies:
            J = sysl.bodies[b.name][2]
            theta[:, i] += rec_q @ J[2]
            omega[:, i] += rec_v @ J[2]
    # frame rotation: the carrier's nominal turn (planetary), none for a spur pair
    ic = next((i for i, b in enumerate(model.bodies) if b.name == "carrier"), None)
    rot = (theta[:, ic] - lm.frame_angle) if ic is not None else np.zeros(ns)
    c, s = np.cos(rot), np.sin(rot)
    pos = np.zeros((ns, nb_, 2))
    vel = np.zeros((ns, nb_, 2))
    for i, b in enumerate(model.bodies):
        if b.parent < 0:
            anchor = np.broadcast_to(np.asarray(b.pin, float), (ns, 2)).copy()
            avel = np.zeros((ns, 2))
        else:
            p = b.parent
            cp, sp = np.cos(theta[:, p]), np.sin(theta[:, p])
            rx = cp * b.pin[0] - sp * b.pin[1]
            ry = sp * b.pin[0] + cp * b.pin[1]
            anchor = pos[:, p] + np.stack([rx, ry], axis=1)
            avel = vel[:, p] + omega[:, p, None] * np.stack([-ry, rx], axis=1)
        dev = np.zeros((ns, 2))
        dvel = np.zeros((ns, 2))
        if b.joint == BEARING and b.name in sysl.bodies:
            J = sysl.bodies[b.name][2]
            # translation of the centre relative to its anchor, in the reference frame, turned
            ux = rec_q @ J[0] - (0.0 if b.parent < 0 else rec_q @ _anchor_row(lm, i, 0))
            uy = rec_q @ J[1] - (0.0 if b.parent < 0 else rec_q @ _anchor_row(lm, i, 1))
            vx = rec_v @ J[0] - (0.0 if b.parent < 0 else rec_v @ _anchor_row(lm, i, 0))
            vy = rec_v @ J[1] - (0.0 if b.parent < 0 else rec_v @ _anchor_row(lm, i, 1))
            dev = np.stack([c * ux - s * uy, s * ux + c * uy], axis=1)
            dvel = np.stack([c * vx - s * vy, s * vx + c * vy], axis=1)
        pos[:, i] = anchor + dev
        vel[:, i] = avel + dvel
    body[:, :, 0:2] = pos
    body[:, :, 2] = theta
    body[:, :, 3:5] = vel
    body[:, :, 5] = omega
    db = model.bodies[lm.drive]
    body[:, lm.drive, 6] = rec_F @ lm.drive_arm + db.inertia * acc
    mesh = np.zeros((ns, len(model.meshes), 3))
    mesh[:, :, 0] = np.abs(rec_F)  # normal force on either flank (pair_side tells which)
    nx = c[:, None] * lm.normals[None, :, 0] - s[:, None] * lm.normals[None, :, 1]
    ny = s[:, None] * lm.normals[None, :, 0] + c[:, None] * lm.normals[None, :, 1]
    if tangential is None:
        mesh[:, :, 1] = -rec_F * nx
        mesh[:, :, 2] = -rec_F * ny
    else:
        mesh[:, :, 1] = -rec_F * nx - tangential * ny
        mesh[:, :, 2] = tangential * nx - rec_F * ny
    return body, mesh


def _anchor_row(lm: LumpedModel, i: int, axis: int) -> np.ndarray:
    """Row of the anchor point's Jacobian (global axis) of body i in the lumped coordinates."""
    model, sysl = lm.model, lm.system
    b = model.bodies[i]
    p = model.bodies[b.parent]
    Jp = sysl.bodies[p.name][2]
    th = p.theta0  # the reference position's parent angle
    cp, sp = math.cos(th), math.sin(th)
    rx = cp * b.pin[0] - sp * b.pin[1]
    ry = sp * b.pin[0] + cp * b.pin[1]
    return Jp[0] - ry * Jp[2] if axis == 0 else Jp[1] + rx * Jp[2]
