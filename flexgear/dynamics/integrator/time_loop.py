"""Time integration: HHT-alpha with Newton iterations and one-pass steps, compiled.

Solves ``M(q) q'' = Q(q, q', t) - sum_b J_b^T M_b gamma_b`` in the coordinates of
:mod:`flexgear.dynamics.model.bodies`; a step whose Newton iteration fails is retried with half
the step down to step/64, then the run stops with a :class:`~flexgear.errors.DivergenceError`.
Models with flexible bodies accept a step after one Newton correction when the contraction
estimates and :func:`linearised_acceptance` allow it. See the theory page *The integrator*.

The whole time loop runs in numba on named tables (:mod:`flexgear.dynamics.model.tables`,
:mod:`.buffers`)::

    forces(q, qd, t, model, contact, work, local)      kinematics, applied_torques,
                                                       torsional_supports, bearings,
                                                       tooth_contact, generalised_forces
    integrate(q, v, acc, t0, nsteps, model,            predict, forces, newton_update,
              compliant, contact, work, settings,      record
              records, stats)

For kernel authors: every array handed to a compiled function (also inside a table) costs an
atomic reference-count increment and decrement per call, so the kernels run every iteration or
step that create no arrays (:func:`~.forces.forces` and what it inlines,
:func:`~flexgear.dynamics.flexible.compliant.compliant_contacts`, the contact search,
:func:`~.records.record`) are compiled with ``_nrt=False``: they take only views of their
arguments and copy element by element (a slice copy may allocate). The sub-kernels of
:func:`~.forces.forces` are ``inline="always"`` and take only the parts of the tables they use.
"""
from __future__ import annotations

import math

import numpy as np

from ...kernels import kernel
from ..flexible.condensed import INTEGRATED, STATIC, accept_condensed, start_condensed, static_condensed
from .forces import forces
from .hht import hht_coefficients, newton_update, predict
from .kinematics import kinematics
from .one_pass import linearised_acceptance
from .records import condensed_drive_torque, modal_drive_torque, record, record_condensed, record_friction

# the contraction estimates of the Newton iteration (second correction over the first, and over
# its square) keep the largest sample, decayed by this factor at each new sample (one every
# CALIBRATE_STEPS steps): a step that contracted badly holds one-pass steps back for a while
CONTRACTION_DECAY = 0.5
# a step with a full contact search, one in about CALIBRATE_STEPS steps (every
# max(1, CALIBRATE_STEPS // full_every)-th full search: 800 us at the flexible presets' 6.25 us,
# about 2.4 samples per sun-planet mesh period of MERCURY 1-A), always iterates to sample the
# contraction (one in 32 steps cost about 2 % more force evaluations on MERCURY 1-A)
CALIBRATE_STEPS = 128
# one-pass mode: a converged step that cannot move its records to the accepted state
# (linearised_acceptance refuses) evaluates once more unless its last correction is below
# LAST_ITERATE x tol (then its records are at an iterate that close to the accepted state)
LAST_ITERATE = 1e-3
# error codes returned by the kernel
OK, ERR_NEWTON, ERR_NAN, ERR_PENETRATION = 0, 1, 2, 3


@kernel(error_model="numpy")
def _stop(stats, code, t, where):
    """Store an error (code, time [s], mesh) in the statistics and return its code."""
    stats.error_code[0] = code
    stats.error_time[0] = t
    stats.error_mesh[0] = where
    return code


@kernel(error_model="numpy")
def integrate(q, v, acc, t0, nsteps, model, compliant, contact, work, settings, records, stats):
    """Advance (q, v, acc) from t0 by nsteps steps of settings.h with the buffers ``work`` (a Workspace).

        Each step: predictor (:func:`~.hht.predict`), forces (:func:`~.forces.forces`, a full contact
        search in the first iteration every ``settings.full_every`` steps, local ones otherwise) and
        Newton updates (:func:`~.hht.newton_update`) until the position change is below
        ``settings.tol`` [m], halving a failed step down to h/64; then :func:`~.records.record` into
        ``records`` (a :class:`~flexgear.dynamics.integrator.buffers.Records` window starting at this
        call's first step; contact pairs and condensed modes every out_every steps).
        ``stats`` (:class:`~flexgear.dynamics.integrator.buffers.Statistics`) counts steps and
        iterations and receives the error code, time and mesh. Returns the error code (0 = OK).

        With ``settings.one_pass`` a step without a full search and not retried is accepted after
        its first correction d1 when ``max(rho d1, rho2 d1^2) < settings.tol``, rho [-] and rho2
        [1/m] the largest contraction ratios of the steps that iterated (decayed by
        ``CONTRACTION_DECAY`` per sample; a full-search step, one in about ``CALIBRATE_STEPS``,
        iterates to sample them), and :func:`linearised_acceptance` holds; the records and carried
        state are then corrected to first order (``stats.linearised`` counts these steps).
        ``compliant`` is ``model.compliant``: None where no mesh is compliant, and numba then prunes
        at compile time the one-pass acceptance (a rigid model iterates every step fully) and the
        condensed modes, whose loads only the compliant contact solve computes (without it they
        stay 0).
    """
    n = q.shape[0]
    h = settings.h
    alpha = settings.alpha
    tol = settings.tol
    max_newton = settings.max_newton
    depth_limit = settings.depth_limit
    full_every = settings.full_every
    calibrate_every = max(1, CALIBRATE_STEPS // full_every)
    out_every = settings.out_every
    scale = settings.scale
    rotation = model.bodies.rotation
    inertia = model.bodies.inertia
    state = work.bodies
    system = work.system
    contacts = work.contacts
    rhs = system.rhs
    md = contacts.max_depth
    beta, gamma_ = hht_coefficients(alpha)
    rhs_n = np.zeros(n)
    # Condensed modes integrated in the contact solve (condensed.py): the frames' inertia load
    # on them is taken at the step's end, with the Newton iterate a (d a / dq = 1 / (beta h^2)),
    # and the forces at the start are those of the modes' accepted state (step 0). Condensed
    # quasi-statically, the inertia load acts like a mass too: in the HHT residual (1 + alpha)
    # F_n+1 - alpha F_n it must come out as the load of a_n+1, so each evaluation takes a_used =
    # (a + alpha a_used_n) / (1 + alpha); state.accelerations holds a_used of the last accepted
    # state (simulate sets it to acc before the first call)
    cst = work.condensed
    integrated = settings.condensation == INTEGRATED
    cst.alpha[0] = alpha
    cst.step[0] = 0.0
    a_used = state.accelerations.copy()
    state.acceleration_slope[0] = 0.0
    if compliant is not None:  # condensed modes (a model with compliant meshes; pruned in a rigid time loop)
        if integrated and cst.started[0] == 0:  # the first call: the modes start at their static response
            cst.mode[0] = STATIC
            forces(q, v, t0, model, contact, work, False)
            static_condensed(model.flex, cst)
    cst.mode[0] = settings.condensation
    forces(q, v, t0, model, contact, work, False)
    rhs_n[:] = rhs
    if compliant is not None:
        if integrated:
            start_condensed(model.flex, cst)
    t = t0
    qn = q.copy()
    vn = v.copy()
    an = acc.copy()
    a = np.zeros(n)
    qq = np.zeros(n)
    vv = np.zeros(n)
    since_full = 0
    retry = False
    # one pass (settings.one_pass): the contraction estimates (-1: no sample yet) and work arrays
    one_pass = settings.one_pass != 0 and integrated
    rho = -1.0
    rho2 = -1.0
    dq_first = 0.0
    full_step = False
    fulls = 0
    linear_record = False
    a0 = np.zeros(n)
    da = np.zeros(n)
    dqv = np.zeros(n)
    dvv = np.zeros(n)
    for k in range(nsteps):
        t_target = t0 + (k + 1) * h
        hl = h
        # a remainder below 1e-6 h is round-off of t (about 1e-16 t), not a step to take: a
        # sub-step of 1e-17 s would make HHT's acceleration jump
        while t < t_target - 1e-6 * h:
            if t + hl > t_target - 1e-6 * h:
                hl = t_target - t
            # Newton on the new acceleration
            a[:] = an
            conv = False
            fin = True
            it = 0
            where = -1
            linear = False
            while it < max_newton:
                it += 1
                predict(qn, vn, an, a, hl, beta, gamma_, qq, vv)
                full = it == 1 and (since_full >= full_every or retry)
                if full:
                    since_full = 0
                    full_step = fulls % calibrate_every == 0  # this step iterates: a contraction sample
                    fulls += 1
                elif it == 1:
                    full_step = False
                if integrated:
                    state.accelerations[:] = a
                    state.acceleration_slope[0] = 1.0 / (beta * hl * hl)
                    cst.step[0] = hl
                else:
                    for j in range(n):
                        state.accelerations[j] = (a[j] + alpha * a_used[j]) / (1.0 + alpha)
                    state.acceleration_slope[0] = 1.0 / ((1.0 + alpha) * beta * hl * hl)
                where = forces(qq, vv, t + hl, model, contact, work, not full)
                if one_pass:
                    a0[:] = a
                dq, fin = newton_update(system, rhs_n, a, alpha, beta, gamma_, hl, scale, model.housing)
                if not fin:
                    break
                if one_pass:
                    for j in range(n):  # the correction, for linearised_acceptance
                        da[j] = a[j] - a0[j]
                        dqv[j] = beta * hl * hl * da[j]
                        dvv[j] = gamma_ * hl * da[j]
                    if it == 1:
                        dq_first = dq
                    elif it == 2 and dq_first > 0.0:  # a sample of the contraction
                        r = dq / dq_first
                        rho = max(r, CONTRACTION_DECAY * rho)
                        rho2 = max(r / dq_first, CONTRACTION_DECAY * rho2)
                if dq < tol:
                    if one_pass:  # the records and the carried state at the accepted state too
                        if compliant is not None:  # pruned in a rigid time loop (one_pass is 0 there)
                            linear = linearised_acceptance(a, da, dqv, dvv, dq, rhs_n, alpha, model, work)
                        if not linear and dq > LAST_ITERATE * tol and it < max_newton:
                            continue  # one more evaluation, at an iterate this close to the accepted state
                    conv = True
                    break
                if compliant is not None:  # pruned in a rigid time loop
                    if (one_pass and it == 1 and not full_step and not retry and rho >= 0.0
                            and max(rho * dq, rho2 * dq * dq) < tol
                            and linearised_acceptance(a, da, dqv, dvv, dq, rhs_n, alpha, model, work)):
                        conv = True
                        linear = True
                        stats.linearised[0] += 1
                        break
            stats.newton[0] += it
            if it > stats.max_iter[0]:
                stats.max_iter[0] = it
            if md[0] > depth_limit:
                return _stop(stats, ERR_PENETRATION, t + hl, where)
            if not conv:
                stats.rejected[0] += 1
                retry = True
                hl = 0.5 * hl
                if hl < h / 64.0:
                    return _stop(stats, ERR_NEWTON if fin else ERR_NAN, t, where)
                continue
            # accept: the state at t + hl; forces and records are those of the last Newton
            # evaluation (one pass: moved to the accepted state, linearised_acceptance; else up
            # to the tolerance from it)
            retry = False
            since_full += 1
            linear_record = linear
            predict(qn, vn, an, a, hl, beta, gamma_, qq, vv)
            for j in range(n):
                if not (math.isfinite(qq[j]) and math.isfinite(vv[j])):
                    return _stop(stats, ERR_NAN, t + hl, -1)
            if compliant is not None:
                if integrated and not accept_condensed(model.flex, cst, hl):
                    return _stop(stats, ERR_NAN, t + hl, -1)
            qn[:] = qq
            vn[:] = vv
            an[:] = a
            a_used[:] = state.accelerations
            rhs_n[:] = rhs
            t += hl
            stats.steps[0] += 1
            if hl < h:
                hl = min(2.0 * hl, h)
        t = t_target  # no drift of t from summed sub-steps
        if compliant is not None:  # one-pass steps only (pruned in a rigid loop, with the kinematics inlined here)
            if linear_record:  # the records' poses and coordinates at the accepted state itself
                kinematics(qn, vn, t, model.bodies, model.profiles, state)
                state.coordinates[:] = qn
                state.rates[:] = vn
        record(k, rotation, inertia, state, contacts, out_every, records)
        record_friction(k, work.friction, contacts.count, out_every, records)
        nmod = records.modal.shape[1]
        for j in range(nmod):
            records.modal[k, j] = state.coordinates[n - nmod + j]
        modal_drive_torque(k, an, model.flex, rotation, records)
        if compliant is not None:  # the condensed modes (pruned in a rigid time loop)
            if (k + 1) % out_every == 0:
                record_condensed((k + 1) // out_every - 1, model.flex, cst, state, integrated, records.condensed)
            if integrated:
                condensed_drive_torque(k, model.flex, cst, rotation, records)
    q[:] = qn
    v[:] = vn
    acc[:] = an
    return OK
