"""Simulation of a model: the Python driver of the compiled time loop (:mod:`~flexgear.dynamics.integrator.time_loop`), in
chunks with progress, the thread choice, the initial state, single force evaluations and the
records turned into results.
"""
from __future__ import annotations

import time as _time

import numba as nb
import numpy as np

from ...errors import DivergenceError
from ...kernels import compile_seconds as kernel_seconds, is_cached, overload_state
from ..contact.laws import LAW_HERTZ
from ..flexible.condensed import INTEGRATED, STATIC
from ..model.bodies import Model
from ..threads import SpareCores, available_threads, check_threads, kernel_threads
from .buffers import Settings, records as new_records, statistics as new_statistics, workspace
from .forces import forces
from .time_loop import ERR_NAN, ERR_PENETRATION, OK, integrate

# a full contact search every FULL_SEARCH_INTERVAL of simulated time (full_search_every: 8 steps at
# the rigid presets' 25 us step, 32 at the flexible presets' 6.25 us); in between the contacts and
# the near-contacts within CACHE_SAMPLES samples are followed locally. A surface not followed would
# have to close 160 um in 200 us (0.8 m/s) to be missed for a step. The margin is a closing speed,
# so the interval is one of time, not of steps: 8 steps at any step gave the flexible presets 4 x
# the rigid baseline's margin for 4 x its full searches (on MERCURY 1-A about 6 % of a force
# evaluation; the same contacts over 0.12 s of both flexible presets either way).
FULL_SEARCH_INTERVAL = 200e-6  # s
# a full search scans every COARSE_STRIDE-th outline sample first (320 um at the default module/200
# spacing: the SDF is 1-Lipschitz, so a half tooth whose scanned samples all lie farther than
# half of that cannot touch), then refines around the nearest
COARSE_STRIDE = 32


def full_search_every(h: float) -> int:
    """Steps between two full contact searches at step ``h`` [s]: ``FULL_SEARCH_INTERVAL / h``
    rounded, at least 1 (8 at 25 us, 32 at 6.25 us)."""
    return max(1, int(round(FULL_SEARCH_INTERVAL / h)))


#: ``simulate(condensation=...)``: the codes of :class:`~flexgear.dynamics.integrator.buffers.Settings`
CONDENSATION = {"static": STATIC, "integrated": INTEGRATED}


# ---------------------------------------------------------------------------------------------
# Forces: kinematics, applied torques, supports, bearings, tooth contact, generalised forces


# ---------------------------------------------------------------------------------------------
# Time integration: HHT coefficients, predictor, Newton, recording


# ---------------------------------------------------------------------------------------------
# Python entry points


def initial_acceleration(model: Model, arr=None, tables=None, q=None, v=None, stride=COARSE_STRIDE, t=0.0,
                         acceleration_slope=0.0, friction=None):
    """Solve Mq a0 = rhs(q0, v0, t) (default: the model's initial state at t = 0).

    Parameters
    ----------
    model : Model
    arr : KernelModel, optional
        ``model.pack(stride)`` if given.
    tables : ContactTables, optional
        Default ``model.tables``.
    acceleration_slope : float
        d q'' / dq assumed in the tangent (:class:`~flexgear.dynamics.integrator.buffers.BodyState`; the
        integrator's 1 / ((1 + alpha) beta h^2)). With 1, Kt includes ``-dQ/dq''`` of the frames' inertia
        load on condensed modes (:func:`~flexgear.dynamics.flexible.compliant.inertia_flank_value`); the
        accelerations themselves are taken as zero [1/s^2].
    friction : RigidFriction, optional
        Tooth friction of the meshes, IMPACT and compliant
        (:func:`~flexgear.dynamics.integrator.friction.rigid_friction`); default frictionless.

    Returns
    -------
    acc : (n,) array
        Generalised accelerations [m/s^2, rad/s^2].
    work : Workspace
        The force evaluation (poses, loads, matrices, contacts).
    """
    if q is None or v is None:
        q0, v0 = model.initial_state()
        q = q0 if q is None else q
        v = v0 if v is None else v
    work = _evaluated(model, arr, tables, q, v, stride, t, acceleration_slope, friction)
    return np.linalg.solve(work.system.mass, work.system.rhs), work


def _evaluated(model: Model, arr, tables, q, v, stride: int, t: float, acceleration_slope: float, friction):
    """The Workspace of one force evaluation in state (q, v) at time t (arguments as
    :func:`initial_acceleration`)."""
    if arr is None:
        arr = model.pack(stride)
    if tables is None:
        tables = model.tables
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    work = model_workspace(model, arr, len(q), friction)
    work.bodies.acceleration_slope[0] = float(acceleration_slope)
    forces(q, v, float(t), arr, tables, work, False)
    return work


def model_workspace(model: Model, arr, n: int, friction=None):
    """Zeroed buffers (:func:`~flexgear.dynamics.integrator.buffers.workspace`) sized for the model and its
    tables ``arr`` (KernelModel) with n coordinates; ``friction``: the RigidFriction of its meshes,
    IMPACT or compliant (None: frictionless)."""
    return workspace(n, len(model.bodies), len(model.meshes), int(arr.flex.condensed.max(initial=0)),
                     int(np.count_nonzero(arr.meshes.law == LAW_HERTZ)), int(arr.flex.body.size),
                     int(arr.flex.condensed.sum()), friction)


def evaluate(model: Model, q, v, t=0.0, stride=COARSE_STRIDE, acceleration_slope=0.0, friction=None, arr=None):
    """Forces and contacts of the model in state (q, v) at time t (for checks, tests and the
    static equilibria; ``acceleration_slope``: see :func:`initial_acceleration`; ``arr``:
    ``model.pack(stride)``, packed once by a caller that evaluates one model many times).

    Returns a dict with the body loads ``Fb`` (nb, 3), mesh totals ``mesh`` (nm, 3: normal force
    sum, Fx, Fy on body b), contact arrays ``cf`` (nm, MAXC, 6: force, depth, px, py, nx, ny),
    ``ci`` (nm, MAXC, 3: tooth a, tooth b, side a), counts ``count``, ``max_depth`` and the
    whole :class:`~flexgear.dynamics.integrator.buffers.Workspace` as ``work`` (with ``friction``,
    a RigidFriction, the contacts' friction in ``work.friction``).
    """
    work = _evaluated(model, arr, None, q, v, stride, t, acceleration_slope, friction)
    b, s, c = work.bodies, work.system, work.contacts
    cf = np.stack([c.force, c.depth, c.x, c.y, c.nx, c.ny], axis=-1)
    ci = np.stack([c.tooth_a, c.tooth_b, c.side_a], axis=-1)
    mesh = np.stack([c.mesh_force, c.mesh_fx, c.mesh_fy], axis=-1)
    return dict(pose=b.pose, vel=b.vel, Fb=b.load, rhs=s.rhs, Mq=s.mass, Kt=s.stiffness, Ct=s.damping, cf=cf, ci=ci,
                count=c.count, mesh=mesh, max_depth=c.max_depth[0], work=work)


class Integration:
    """Result of :func:`simulate`: raw records on the integration grid plus statistics.

    ``mesh`` (nsteps, nm, 3: normal force sum, Fx, Fy on body b), ``body`` (nsteps, nb, 7: x,
    y, theta, vx, vy, omega, drive torque), ``pair_f`` (nout, nm, MAXC, 2: force, depth),
    ``pair_i`` (nout, nm, MAXC, 3: tooth a, tooth b, side a) stack the named ``records``.
    ``modal`` (nsteps, m) holds the modal coordinates in q at every step (then a coupled
    housing's coordinates, ``model.housing.n`` of them), ``condensed`` (nout,
    sum nq) the condensed modes' eta_i [sqrt(kg) m] at the pair samples (instantaneous; body
    f's at ``model.pack().flex.condensed_offset[f]``, in the order of ``model.flex``): with
    ``condensation`` "integrated" their state, with "static" their static response to the
    contact forces and the frame's inertia load (:func:`record_condensed`). With tooth friction
    ``friction`` is a dict as the lumped model's (:func:`friction_result`), else None; with the
    squeeze-film damping ``damping`` a dict (:func:`damping_result`), else None.
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)


def simulate(model: Model, t_end: float, h: float, out_every: int, alpha: float = -0.1, tol: float = 1e-10,
             max_newton: int = 12, stride: int = COARSE_STRIDE, chunk_steps: int = 2000, progress=None,
             depth_limit: float | None = None, full_every: int | None = None, q0=None,
             v0=None, condensation: str = "integrated", one_pass: bool | None = None,
             threads: int | None = None, friction=None, on_solver=None) -> Integration:
    """Integrate the model from 0 to t_end with step h [s] (t_end/h steps, a multiple of out_every).

        Parameters
        ----------
        progress : callable(fraction) or None
            Called after every chunk with the simulated fraction done.
        depth_limit : float
            Penetration [m] beyond which the run is declared diverged (default: a quarter module of
            the first mesh's gears).
        full_every : int, optional
            Steps between two full contact searches (default: :func:`full_search_every` of h, one
            every 200 us of simulated time).
        q0, v0 : (n,) arrays, optional
            Initial coordinates and velocities (default: ``model.initial_state()``).
        condensation : {"integrated", "static"}
            The flexible bodies' condensed modes: integrated in the contact solve with their own
            inertia (:mod:`~flexgear.dynamics.flexible.condensed`) or quasi-statically.
        one_pass : bool, optional
            Accept a step after its first Newton correction when the contraction shows the next
            one below ``tol`` (:func:`linearised_acceptance`). Default: on for a model with a
            compliant mesh (a flexible gear) and ``condensation="integrated"``; a model without one
            iterates fully (True raises ValueError: its solver is compiled without one-pass steps).
        threads : int or "auto", optional
            Threads of the force evaluation of the compliant meshes
            (:mod:`~flexgear.dynamics.threads`); 1 or None (default): serial; at most
            ``NUMBA_NUM_THREADS``. Serial is the default because threads spin for a time slice when
            the machine becomes loaded, and a parallel chunk can then run many times slower.
            ``"auto"``: :class:`ThreadChoice` times chunks with all threads and with one, keeps the
            faster and rechecks every :data:`RECHECK_CHUNKS` chunks. Results are bit-identical
            whatever the count (every sum is formed in one thread, in serial order).
        friction : RigidFriction, optional
            Tooth friction of the meshes, IMPACT and compliant
            (:func:`~flexgear.dynamics.integrator.friction.rigid_friction`; default frictionless).
        on_solver : callable(str), optional
            Told, before the time loop is compiled or loaded, where this model's loop comes from:
            ``"compiled"`` in this process, ``"cached"`` on disk or ``"compile"`` (its first run of
            this kind on the machine; :func:`flexgear.kernels.overload_state`).

        Raises
        ------
        DivergenceError
            With the simulated time, the mesh or coordinate and the cause.

        Notes
        -----
        ``wall`` [s] times the integration only; compiling or loading the force kernels and the
        time loop is ``compile_seconds`` (0 when already compiled in this process).
    """
    if condensation not in CONDENSATION:
        raise ValueError(f"condensation = {condensation!r}: must be one of {sorted(CONDENSATION)}")
    threads = check_threads(threads)
    kmodel = model.pack(stride)
    has_compliant = kmodel.compliant is not None
    if one_pass and not has_compliant:
        raise ValueError("one_pass = True: one-pass steps move the compliant contacts of flexible gears; this "
                         "model has no compliant mesh (its time loop is compiled without them)")
    tables = model.tables
    q, v = model.initial_state()
    if q0 is not None:
        q = np.array(q0, float).reshape(q.shape)
    if v0 is not None:
        v = np.array(v0, float).reshape(v.shape)
    n = len(q)
    nb_, nm = len(model.bodies), len(model.meshes)
    nsteps = int(round(t_end / h))
    nsteps -= nsteps % out_every
    if full_every is None:
        full_every = full_search_every(h)
    if int(full_every) < 1:
        raise ValueError(f"full_every = {full_every}: the steps between two full contact searches must be at least 1")
    if depth_limit is None:
        depth_limit = model.attrs.get("depth_limit", 5e-4)
    scale = np.ones(n)
    for i, name in enumerate(model.coordinate_names()):
        if name.endswith(".theta"):
            scale[i] = model.length_scale
    modal = model.modal_coordinates()
    flex_of = {fb.body: fb for fb in model.flex}
    for body, c0, m in modal:  # flank displacement per unit modal coordinate
        scale[c0:c0 + m] = flex_of[body].modal_scale
    nmod = sum(m for _, _, m in modal)
    if model.housing is not None:  # recorded with the modal coordinates (the last of q): Integration.modal
        scale[n - model.housing.n:] = model.housing.scale
        nmod += model.housing.n
    ncond = int(kmodel.flex.condensed.sum())
    settings = Settings(h=float(h), alpha=float(alpha), tol=float(tol), max_newton=int(max_newton),
                        depth_limit=float(depth_limit), full_every=int(full_every), out_every=int(out_every),
                        scale=scale, condensation=CONDENSATION[condensation],
                        one_pass=int(has_compliant if one_pass is None else bool(one_pass))
                        * (condensation == "integrated"))
    rubs = friction is not None and bool(np.any(friction.on))
    squeeze = friction is not None and bool(np.any(friction.squeeze))
    rec = new_records(nsteps, nsteps // out_every, nb_, nm, nmod, ncond, rubs, squeeze)
    stats = new_statistics()
    compile_seconds = kernel_seconds()
    # compile (or load) this model's time loop first, so that its force kernels compile inside it (a
    # force kernel compiled or loaded alone first, by initial_acceleration below, would be compiled
    # once more for the time loop: kernels.KernelDispatcher.compile); in every run, as the time loop
    # may hold only another model's overload; with no step it evaluates the forces once, on copies
    first = (q.copy(), v.copy(), np.zeros(n), 0.0, 0, kmodel, kmodel.compliant, tables,
             model_workspace(model, kmodel, n, friction), settings, rec.window(0, 0, out_every), new_statistics())
    if on_solver is not None:
        on_solver(overload_state(integrate, first))
    integrate(*first)
    try:
        acc, _ = initial_acceleration(model, kmodel, tables, q, v, stride, friction=friction)
    except np.linalg.LinAlgError:
        acc = np.full(n, np.nan)
    compile_seconds = kernel_seconds() - compile_seconds
    if not np.all(np.isfinite(acc)):
        raise DivergenceError(
            "simulation diverged at t = 0.000000 s in the bodies' coordinates: the initial accelerations are not "
            "finite (a singular mass matrix or non-finite forces: check masses, inertias, densities, loads and "
            "contact parameters for extreme values)")
    work = model_workspace(model, kmodel, n, friction)
    work.bodies.accelerations[:] = acc  # the start's (see integrate)
    wall0 = _time.perf_counter()
    done = 0
    t = 0.0
    chunk = max(out_every, (chunk_steps // out_every) * out_every)
    # (threads only matter to the compliant meshes' evaluation: a model without any runs serial)
    auto = threads == "auto"
    pick = ThreadChoice(((available_threads() if auto else threads or 1) if np.any(kmodel.meshes.law == LAW_HERTZ)
                         else 1), fixed=not auto)
    while done < nsteps:
        k = min(chunk, nsteps - done)
        use = pick.next()
        work.contacts.threads[0] = use
        try:
            c0 = _time.perf_counter()
            with kernel_threads(use):
                code = integrate(q, v, acc, t, k, kmodel, kmodel.compliant, tables, work, settings,
                                 rec.window(done, k, out_every), stats)
            pick.timed(use, (_time.perf_counter() - c0) / k)
        except np.linalg.LinAlgError:  # raised by the compiled solve on a non-finite Newton matrix
            raise DivergenceError(
                f"simulation diverged at t = {t:.6f} s (within the next {k * h:.3g} s) in the bodies' coordinates: "
                "the Newton matrix became non-finite (NaN/inf); check masses, inertias, loads and contact "
                "parameters for extreme values"
                + largest_modal_coordinate(model, work.bodies.coordinates, work.condensed.position)) from None
        if code != OK:
            tt = stats.error_time[0]
            wm = int(stats.error_mesh[0])
            where = f"mesh '{model.meshes[wm].name}'" if 0 <= wm < nm else "the bodies' coordinates"
            if code == ERR_PENETRATION:
                cause = (f"tooth penetration exceeded the limit {depth_limit*1e3:.3g} mm (the gears pass through "
                         "each other: load too high for the contact stiffness, or a step too large)")
            elif code == ERR_NAN:
                cause = "the state became non-finite (NaN/inf)"
            else:
                cause = (f"Newton's method did not converge in {max_newton} iterations even with the step "
                         f"reduced to {h/64:.3g} s")
            raise DivergenceError(f"simulation diverged at t = {tt:.6f} s in {where}: {cause}"
                                  + largest_modal_coordinate(model, work.bodies.coordinates, work.condensed.position))
        done += k
        t = done * h
        if progress is not None:
            progress(done / nsteps)
    wall = _time.perf_counter() - wall0
    return Integration(h=h, nsteps=nsteps, out_every=out_every,
                       mesh=np.stack([rec.mesh_force, rec.mesh_fx, rec.mesh_fy], axis=-1),
                       body=np.stack([rec.x, rec.y, rec.theta, rec.vx, rec.vy, rec.omega, rec.torque], axis=-1),
                       pair_f=np.stack([rec.pair_force, rec.pair_depth], axis=-1),
                       pair_i=np.stack([rec.pair_tooth_a, rec.pair_tooth_b, rec.pair_side_a], axis=-1),
                       records=rec, steps=int(stats.steps[0]), newton=int(stats.newton[0]),
                       rejected=int(stats.rejected[0]), max_iter=int(stats.max_iter[0]),
                       linearised=int(stats.linearised[0]), wall=wall,
                       compile_seconds=compile_seconds, q=q, v=v, modal=rec.modal, condensed=rec.condensed,
                       condensation=condensation, friction=friction_result(rec) if rubs else None,
                       damping=damping_result(rec) if squeeze else None)


def friction_result(rec) -> dict:
    """The tooth friction of a rigid or flexible run's records ``rec``, as the lumped model gives it
    (:func:`flexgear.dynamics.lumped.friction.friction_records`): per step ``force`` (nsteps, nm),
    the friction force of body a on body b along the flank tangent summed over the contacts [N];
    ``power``, the power it dissipates [W]; ``through``, the power the normal forces carry
    through the mesh relative to the carrier [W]; at the output samples, per contact slot
    ``sliding`` [m/s], ``position`` [m] (nan: empty slot) and ``pair_force`` [N]."""
    return {"force": rec.friction_force, "power": rec.friction_power, "through": rec.friction_through,
            "sliding": rec.pair_sliding, "position": rec.pair_position, "pair_force": rec.pair_friction}


def damping_result(rec) -> dict:
    """The squeeze-film damping of a rigid or flexible run's records ``rec``: per step ``power`` (nsteps,
    nm), the power the films dissipate [W]; at the output samples ``pair_force`` (nout, nm,
    MAXC), each contact slot's squeeze-film force along the normal [N] (0: empty slot)."""
    return {"power": rec.damping_power, "pair_force": rec.pair_damping}


#: chunks between two timings of the thread count not in use (:func:`simulate`)
RECHECK_CHUNKS = 20


class ThreadChoice:
    """The thread count of :func:`simulate`'s next chunk.

    ``fixed``: always that count. Otherwise (``most`` threads available, > 1) the first chunk
    runs with ``most`` threads and the second with one, then the faster of the two per step
    (wall time), the other timed again every :data:`RECHECK_CHUNKS` chunks; a chunk that would
    run on n > 1 threads runs on one unless the other processes left n - 1/2 cores idle during
    the last chunk (``spare``, default :class:`~flexgear.dynamics.threads.SpareCores`: threads
    waiting for a time slice make a parallel step several times slower than a serial one, and
    a chunk cannot be cut short). The results do not depend on the choice."""

    def __init__(self, most: int, fixed: bool = False, spare=None):
        self.most = max(1, min(int(most), int(nb.config.NUMBA_NUM_THREADS)))
        self.fixed = fixed
        self.spare = SpareCores() if spare is None else spare
        self.per_step = {}  # threads -> wall time per step of its last chunk [s]
        self.chunks = 0

    def next(self) -> int:
        """The thread count of the next chunk."""
        if self.fixed or self.most == 1:
            return self.most
        i = self.chunks
        self.chunks += 1
        if i == 0:
            want = self.most
        elif i == 1 or not self.per_step:
            want = 1
        else:
            best = min(self.per_step, key=self.per_step.get)
            want = best
            if (i - 1) % RECHECK_CHUNKS == 0:
                want = 1 if best != 1 else self.most
        if want > 1 and self.spare() < want - 0.5:
            return 1
        return want

    def timed(self, threads: int, per_step: float) -> None:
        """The wall time per step [s] of the chunk just run with ``threads``."""
        self.per_step[threads] = per_step


def largest_modal_coordinate(model: Model, q, condensed=None) -> str:
    """Text naming the flexible body and mode with the largest flank displacement among the
    modal coordinates in q and, if ``condensed`` (the condensed modes' eta_i, the
    :class:`~flexgear.dynamics.integrator.buffers.CondensedState` ``position``, in the order of
    ``model.flex``) is given, among the condensed modes: body, mode number in the body's
    reduction, frequency, coordinate and flank displacement ('' for a model with neither)."""
    def largest(candidates):
        best = None
        for u, eta, freq, body, first in candidates:
            if u.size == 0:
                continue
            k = int(np.nanargmax(u)) if np.any(np.isfinite(u)) else 0
            if best is None or not u[k] <= best[0]:
                best = (u[k], body, first + k, float(eta[k]), float(freq[k]))
        return best

    flex_of = {fb.body: fb for fb in model.flex}
    modal = []
    for body, c0, m in model.modal_coordinates():
        eta = np.asarray(q[c0:c0 + m], float)
        modal.append((np.abs(eta) * flex_of[body].modal_scale, eta, flex_of[body].frequencies, body, 0))
    cond, o = [], 0
    for fb in model.flex if condensed is not None else ():
        nq = fb.shape.shape[3]
        if nq and fb.condensed_omega is not None:
            eta = np.asarray(condensed[o:o + nq], float)
            amax = np.abs(fb.shape).reshape(-1, nq).max(axis=0) * fb.condensed_omega  # largest |A_i| on the flanks
            cond.append((np.abs(eta) * amax, eta, fb.condensed_omega / (2.0 * np.pi), fb.body, fb.modes))
        o += nq
    text = ""
    for kind, best in (("modal coordinate", largest(modal)), ("condensed mode", largest(cond))):
        if best is not None:
            u, body, k, eta, f = best
            text += (f"; largest {kind}: body '{model.bodies[body].name}' mode {k + 1} ({f:.4g} Hz), "
                     f"eta = {eta:.4g} sqrt(kg) m, flank displacement up to {u * 1e6:.4g} um")
    return text


ENTRY_KERNELS = (forces, integrate)
"""The kernels Python calls directly (the others are compiled into them)."""


def compiled_cache_present() -> bool:
    """Whether the on-disk cache holds the time loop (else the next run compiles it first)."""
    return all(is_cached(k) for k in ENTRY_KERNELS)
