"""Modal coordinates of flexible gears in the solver (issue 8, item 3).

Modes below ``[flexible] dynamic_cutoff`` are generalised coordinates (unit modal mass,
stiffness omega^2, the Craig-Bampton frame-mode mass coupling); the others stay condensed.
Checks: the dynamic modes against the condensed ones when the step resolves them
(equivalence), the spectrum against the mode cutoff, energy and angular momentum of a free
vibration (conservation laws of the trapezoidal rule on a linear system), the frequency of a
soft gear's mode against the clamped FE eigenvalue (with the Newmark period error in closed
form), bad input and the outputs. FE meshes at level 1 keep the default suite fast.
"""
import copy
import math
import tomllib

import numpy as np
import pytest

from flexgear.config import parse_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator.simulation import evaluate, simulate
from flexgear.errors import ConfigError, DivergenceError

SPUR = tomllib.loads(preset_path("spur_pair").read_text())
COARSE = {"gears": ["pinion", "wheel"], "level": 1, "formulation": "plane_stress"}
MESH_HZ = 240.0  # spur pair: 24 teeth x 10 Hz


def spur(flexible, ramp=0.01):
    doc = copy.deepcopy(SPUR)
    doc["flexible"] = flexible
    doc["load"]["ramp"] = ramp
    return parse_config(doc)


def mesh_lines(cfg, steps_per_mesh, periods=10, settle=0.02, slow_max_hz=5000.0):
    """RMS of the mesh force and the amplitudes of its mesh-frequency harmonics up to 5 kHz
    over ``periods`` whole mesh cycles after ``settle`` seconds (an exact DFT grid: no leakage)."""
    h = 1.0 / (MESH_HZ * steps_per_mesh)
    n_settle = int(round(settle * MESH_HZ)) * steps_per_mesh
    n = periods * steps_per_mesh
    r = simulate(build_model(cfg), (n_settle + n) * h, h, 1)
    F = r.records.mesh_force[-n:, 0]
    spec = np.abs(np.fft.rfft(F)) * 2 / n
    k = np.arange(1, int(slow_max_hz / MESH_HZ) + 1) * periods
    return math.sqrt(np.mean(F ** 2)), spec[k]


def free_model(cfg):
    """The model of ``cfg`` without meshes and applied torques: a free vibration."""
    m = build_model(cfg)
    m.meshes = []
    for b in m.bodies:
        b.torque = None
    return m


# ------------------------------------------------------------------------- equivalence
def test_dynamic_modes_equal_the_condensed_ones_when_the_step_resolves_them():
    """Spur pair, level 1: the modes below 50 kHz (pinion 31.2, 43.9, 43.9 kHz; wheel 43.2 kHz)
    integrated as coordinates with h = 5.2 us (6 steps per period of the 31 kHz mode) against
    all modes condensed. The modes respond to the mesh harmonics (<= 5 kHz) with the dynamic
    amplification 1 / (1 - (f / f_i)^2) - 1 <= 2.6 %, on the modal part of the flank compliance
    (about half of it), plus their inertia loading: so the force RMS agrees within 0.1 % and
    every mesh line below 5 kHz within 2 % of the largest line."""
    rms_c, lines_c = mesh_lines(spur(dict(COARSE, dynamic_cutoff=0.0)), 800)
    cfg = spur(dict(COARSE, dynamic_cutoff=50e3))
    assert len(build_model(cfg).coordinate_names()) == 1 + 4
    rms_d, lines_d = mesh_lines(cfg, 800)
    assert rms_d == pytest.approx(rms_c, rel=1e-3)
    assert np.max(np.abs(lines_d - lines_c)) < 0.02 * lines_c.max()


def test_spectrum_below_5_khz_does_not_change_when_the_cutoff_is_raised():
    """Condensed modes to 100 kHz against 150 kHz: the modes added move compliance from the
    residual tables to the modal part of the same static compliance, so the force RMS and the
    mesh lines below 5 kHz agree within the tables' interpolation (0.5 % of the largest line)."""
    rms_a, lines_a = mesh_lines(spur(dict(COARSE, cutoff=100e3)), 160)
    rms_b, lines_b = mesh_lines(spur(dict(COARSE, cutoff=150e3)), 160)
    assert rms_b == pytest.approx(rms_a, rel=1e-4)
    assert np.max(np.abs(lines_b - lines_a)) < 5e-3 * lines_a.max()


@pytest.mark.slow
def test_spectrum_below_5_khz_with_dynamic_modes_and_a_raised_cutoff_level_2():
    """Level 2 (the presets' mesh), 40 mesh cycles: condensed to 100 kHz, condensed to 200 kHz,
    and the modes below 50 kHz integrated (h = 5.2 us) agree within the bounds above."""
    base = {"gears": ["pinion", "wheel"], "level": 2, "formulation": "plane_strain"}
    rms_a, lines_a = mesh_lines(spur(dict(base, cutoff=100e3)), 160, periods=40)
    rms_b, lines_b = mesh_lines(spur(dict(base, cutoff=200e3)), 160, periods=40)
    assert rms_b == pytest.approx(rms_a, rel=1e-4)
    assert np.max(np.abs(lines_b - lines_a)) < 5e-3 * lines_a.max()
    rms_c, lines_c = mesh_lines(spur(dict(base, dynamic_cutoff=0.0)), 800, periods=40)
    rms_d, lines_d = mesh_lines(spur(dict(base, dynamic_cutoff=50e3)), 800, periods=40)
    assert rms_d == pytest.approx(rms_c, rel=1e-3)
    assert np.max(np.abs(lines_d - lines_c)) < 0.02 * lines_c.max()


# ------------------------------------------------------------------------- free vibration
def _energy(model, q, v):
    """1/2 v^T Mq v + 1/2 eta^T K eta [J] and Mq."""
    e = evaluate(model, q, v)
    E = 0.5 * v @ e["Mq"] @ v
    flex_of = {fb.body: fb for fb in model.flex}
    for body, c0, m in model.modal_coordinates():
        eta = q[c0:c0 + m]
        E += 0.5 * eta @ flex_of[body].stiffness @ eta
    return E, e["Mq"]


def test_free_vibration_keeps_energy_and_angular_momentum():
    """The flexible wheel free to turn on its bearing, three modes as coordinates (43-54 kHz),
    no mesh, no torque, initial modal velocities, HHT alpha = 0 (the trapezoidal rule) with
    h = 1 us. The system is linear (a rotation-only frame: the coupling S_r is constant), so
    Newton is exact and the trapezoidal rule conserves the quadratic energy 1/2 v^T Mq v +
    1/2 eta^T Omega^2 eta exactly: relative drift < 1e-9 over 2000 steps (round-off). The
    angular momentum J theta' + S_r eta' is conserved (< 1e-9 of S_r eta'_0) while the frame
    turns against the modes (theta' leaves 0: the coupling is there). With alpha = -0.1 HHT
    dissipates energy and still conserves the momentum."""
    m = free_model(spur({"gears": ["wheel"], "level": 1, "formulation": "plane_stress", "dynamic_cutoff": 60e3}))
    assert m.coordinate_names() == ["wheel.theta", "wheel.eta1", "wheel.eta2", "wheel.eta3"]
    q, v = m.initial_state()
    v[:] = [0.0, 0.05, -0.03, 0.02]
    E0, M0 = _energy(m, q, v)
    L0 = (M0 @ v)[0]
    assert abs(L0) > 1e-4  # the modes carry angular momentum
    r = simulate(m, 2e-3, 1e-6, 1, alpha=0.0, q0=q, v0=v)
    E1, M1 = _energy(m, r.q, r.v)
    assert abs(E1 / E0 - 1) < 1e-9
    assert abs((M1 @ r.v)[0] - L0) < 1e-9 * abs(L0)
    assert abs(r.v[0]) > 1e-2 * abs(L0) / M0[0, 0]
    r = simulate(m, 2e-3, 1e-6, 1, alpha=-0.1, q0=q, v0=v)
    E2, M2 = _energy(m, r.q, r.v)
    assert E2 < E0 * (1 - 1e-4)
    assert abs((M2 @ r.v)[0] - L0) < 1e-9 * abs(L0)


def test_soft_gear_vibrates_at_its_clamped_fe_frequency():
    """Pinion with the modulus scaled by 0.01 (first clamped mode 3.1 kHz, inside the resolved
    band), frame turned at the prescribed 10 Hz, no mesh; initial displacement of mode 1,
    alpha = 0. The trapezoidal rule turns omega into (2 / h) atan(omega h / 2) in closed form:
    the measured frequency (zero crossings) equals that of the clamped FE eigenvalue within
    1e-5 at h = 20 and 10 us (the neglected gyroscopic coupling is of order Omega / omega_1 =
    3e-3 on the modal stiffness and does not shift a single mode to first order)."""
    cfg = spur({"gears": ["pinion"], "level": 1, "formulation": "plane_stress", "modulus_scale": 0.01,
                "cutoff": 10e3, "dynamic_cutoff": 5e3})
    m = free_model(cfg)
    fb = m.flex[0]
    f1 = fb.frequencies[0]
    assert 2.5e3 < f1 < 3.5e3
    q, v = m.initial_state()
    _, c0, _ = m.modal_coordinates()[0]
    q[c0] = 1e-6
    for h in (2e-5, 1e-5):
        r = simulate(m, 0.02, h, 1, alpha=0.0, q0=q, v0=v)
        x = r.modal[:, 0]
        t = (np.arange(x.size) + 1) * h
        i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
        tz = t[i] - x[i] * h / (x[i + 1] - x[i])
        f_meas = (tz.size - 1) / (2 * (tz[-1] - tz[0]))
        w = 2 * math.pi * f1
        f_trap = 2 * math.atan(w * h / 2) / (2 * math.pi * h)
        assert f_meas == pytest.approx(f_trap, rel=1e-5)
        assert np.abs(x).max() == pytest.approx(1e-6, rel=1e-5)  # no numerical damping at alpha = 0
    # angular momentum balance: the drive holding 10 Hz supplies d/dt (J theta' + S_r eta') =
    # S_r eta'' = -S_r Omega^2 eta (the modes' inertia reaction; nothing else acts). The records
    # are those of the last Newton evaluation, within the Newton tolerance (1e-10 m of flank
    # displacement against an amplitude of 1e-6 max|A_1| = 3e-6 m, 3e-5): bound 1e-4
    i = fb.body
    S_r = fb.frame_coupling[2]
    expected = -(r.modal * np.diag(fb.stiffness)) @ S_r
    torque = r.body[:, i, 6]
    assert np.abs(torque).max() > 1e-3
    assert np.max(np.abs(torque - expected)) < 1e-4 * np.abs(expected).max()


# ------------------------------------------------------------------------- energy of the contact coupling
def test_generalised_modal_force_is_the_work_conjugate_of_the_flank_displacement():
    """Sign check by energy: with a mode as coordinate, the contact's generalised modal force
    Q_i = -dV/d eta_i (V the contact's elastic energy, F = dV/d delta): a finite difference of
    the mesh force along eta_i times the flank displacement law. Equivalently the tangent row is
    symmetric in the rigid angle and the modal coordinate (a conservative contact): Kt[theta,
    eta] = Kt[eta, theta] within 1e-6, and a positive modal coordinate that moves the flank
    away from the mate (A_i > 0) lowers the mesh force."""
    cfg = spur(dict(COARSE, dynamic_cutoff=50e3, search_gap=5e-5))
    m = build_model(cfg)
    q, v = m.initial_state()
    q[0] -= 1.5e-5 / cfg.gears["wheel"].rb
    e = evaluate(m, q, v)
    assert e["mesh"][0, 0] > 100.0
    Kt = e["Kt"]
    for j in range(1, len(q)):
        assert Kt[0, j] == pytest.approx(Kt[j, 0], rel=1e-6, abs=1e-9 * abs(Kt).max())
    # Q_j = -dV/dq_j: central differences of the generalised force against the tangent
    for j in range(1, len(q)):
        d = 1e-9 / max(m.flex[0].modal_scale.max(), m.flex[1].modal_scale.max())
        qp, qm = q.copy(), q.copy()
        qp[j] += d
        qm[j] -= d
        dQ = (evaluate(m, qp, v)["rhs"] - evaluate(m, qm, v)["rhs"]) / (2 * d)
        assert dQ[j] == pytest.approx(-Kt[j, j], rel=1e-3)
        assert dQ[0] == pytest.approx(-Kt[0, j], rel=1e-3)


# ------------------------------------------------------------------------- configuration, outputs, errors
@pytest.mark.parametrize("block, match", [
    ({"dynamic_cutoff": -1.0}, r"flexible.dynamic_cutoff = -1.0: must be >= 0"),
    ({"dynamic_cutoff": float("nan")}, r"flexible.dynamic_cutoff = nan: must be finite"),
    ({"dynamic_cutoff": 2e5}, r"flexible.dynamic_cutoff = 200000.0 Hz: must be <= flexible.cutoff = 100000.0"),
    ({"modal_damping": 1.0}, r"flexible.modal_damping = 1.0: must lie in \[0, 1\)"),
    ({"modal_damping": -0.01}, r"flexible.modal_damping = -0.01: must lie in \[0, 1\)"),
    ({"cutoff": 200e6}, r"flexible.cutoff = 200000000.0 Hz: must be <= 1e\+06 Hz"),  # refused before any meshing
    ({"cutoff": 3.3e6, "modulus_scale": 10.0}, r"must be <= 3.16228e\+06 Hz \(1e\+06 Hz x sqrt\(modulus_scale\)"),
])
def test_bad_dynamic_cutoff_and_modal_damping_are_named(block, match):
    with pytest.raises(ConfigError, match=match):
        spur(dict({"gears": ["pinion"]}, **block))


def test_a_stiffer_modulus_takes_a_cutoff_scaled_with_its_modes():
    """The modes scale with sqrt(E): 100 kHz x sqrt(1000) is the same cutoff for gears 1000 times
    stiffer (tests/test_flexible.py's stiff gears)."""
    assert spur({"gears": ["pinion"], "modulus_scale": 1000.0, "cutoff": 3.16e6}).flexible["cutoff"] == 3.16e6


def test_presets_keep_every_mode_condensed_at_the_default():
    """The flexible presets' dynamic cutoff is 1 / (20 h) at their step (8 kHz at 6.25 us; the
    loader's default 2 kHz is that at its default 25 us): below every clamped mode of the
    presets' gears (31-64 kHz), so the flexible presets add no coordinate."""
    cutoffs = set()
    for name in ("spur_pair_flexible", "mercury_1a_flexible"):
        cfg = parse_config(tomllib.loads(preset_path(name).read_text()))
        assert cfg.flexible["dynamic_cutoff"] == pytest.approx(1.0 / (20 * cfg.simulation["step"]))
        cutoffs.add(cfg.flexible["dynamic_cutoff"])
    doc = copy.deepcopy(SPUR)
    doc["simulation"].pop("step")
    doc["flexible"] = COARSE
    cfg = parse_config(doc)
    assert cfg.flexible["dynamic_cutoff"] == pytest.approx(1.0 / (20 * cfg.simulation["step"]))
    m = build_model(spur(dict(COARSE, dynamic_cutoff=max(cutoffs))))
    assert m.coordinate_names() == ["wheel.theta"]
    assert all(fb.modes == 0 for fb in m.flex)


def test_modal_damping_decays_at_its_ratio():
    """Soft pinion, modal_damping = 0.02, alpha = 0: the envelope of mode 1 decays as
    exp(-zeta omega t) (log decrement over 20 periods within 1 %)."""
    cfg = spur({"gears": ["pinion"], "level": 1, "formulation": "plane_stress", "modulus_scale": 0.01,
                "cutoff": 10e3, "dynamic_cutoff": 5e3, "modal_damping": 0.02})
    m = free_model(cfg)
    f1 = m.flex[0].frequencies[0]
    q, v = m.initial_state()
    _, c0, _ = m.modal_coordinates()[0]
    q[c0] = 1e-6
    h = 2e-6
    r = simulate(m, 20 / f1, h, 1, alpha=0.0, q0=q, v0=v)
    x = r.modal[:, 0]
    peaks = [np.abs(x[k]).max() for k in np.array_split(np.arange(x.size), 20)]
    zeta = math.log(peaks[1] / peaks[-1]) / (2 * math.pi * (len(peaks) - 2))
    assert zeta == pytest.approx(0.02, rel=1e-2)


def test_results_hold_the_modal_coordinates(tmp_path):
    """A run with modal coordinates writes them per flexible body with the mode frequencies
    (layout 3) and reads them back."""
    from flexgear.app.run import run
    from flexgear.results.store import LAYOUT_VERSION, load, save

    doc = copy.deepcopy(SPUR)
    doc["flexible"] = {"gears": ["pinion"], "level": 1, "formulation": "plane_stress", "modulus_scale": 0.5,
                       "cutoff": 80e3, "dynamic_cutoff": 30e3}
    doc["simulation"].update(duration=0.01, run_in=0.01)
    res = run(parse_config(doc))
    body = res.bodies["pinion"]
    f = np.asarray(body.attrs["mode_frequencies"])
    assert f.size >= 1 and np.all(f < 30e3)
    assert body.modal_coordinates.shape == (res.time.size, f.size)
    assert np.abs(body.modal_coordinates).max() > 0
    assert res.bodies["wheel"].modal_coordinates is None
    path = save(res, tmp_path / "results.h5")
    back = load(path)
    assert LAYOUT_VERSION >= 3
    np.testing.assert_array_equal(back.bodies["pinion"].modal_coordinates, body.modal_coordinates)


def test_a_diverging_flexible_run_names_time_mesh_body_and_modal_coordinate():
    """A run that exceeds its penetration limit (set to 20 um here, below the loaded rigid
    overlap of the flexible pair) stops with an error naming when, where, which body and its
    largest modal coordinate."""
    cfg = spur({"gears": ["pinion"], "level": 1, "formulation": "plane_stress", "modulus_scale": 0.5,
                "cutoff": 80e3, "dynamic_cutoff": 30e3})
    m = build_model(cfg)
    assert m.modal_coordinates()
    with pytest.raises(DivergenceError, match=r"diverged at t = \d\.\d+ s in mesh 'pinion-wheel': tooth penetration"
                                              r".*largest modal coordinate: body 'pinion' mode \d+ "
                                              r"\(\d.*Hz\), eta = .*flank displacement up to"):
        simulate(m, 0.02, 2.5e-5, 1, depth_limit=2e-5)


def test_an_inertia_below_what_the_modes_carry_is_refused():
    """A gear inertia set below the share its modal coordinates carry (the first three modes of
    the pinion hold most of its rotational inertia) would make the mass matrix indefinite."""
    doc = copy.deepcopy(SPUR)
    doc["gears"]["pinion"]["inertia"] = 1e-6
    doc["flexible"] = dict(COARSE, dynamic_cutoff=50e3)
    with pytest.raises(ConfigError, match=r"body 'pinion' has mass .* inertia 1e-06 kg m\^2, but its 3 modal "
                                          r"coordinates carry"):
        build_model(parse_config(doc))
