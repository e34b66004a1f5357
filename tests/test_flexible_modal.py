"""Modal analysis of the flexible models (issue 8, item 7): :func:`flexgear.dynamics.modal.linearise.linearise`
with compliant meshes and modal coordinates (the solver's tangent stiffness).

Checks against independent models: the spur pair's torsional mesh mode against the one- and
two-inertia formulas with the static FE loaded mesh's tangent stiffness; with elastic shafts
against a hand-built lumped chain; a soft gear's coupled mode against a free-vibration run of
the same model; MERCURY 1-A against Lin & Parker's lumped model with the flexible model's mesh
stiffnesses (mode types, multiplicities, frequencies). FE meshes at level 1 (reductions cached
on disk) keep the default suite fast.
"""
import copy
import json
import math
import tomllib

import numpy as np
import pytest

from flexgear.config import parse_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.reductions import reduce_flexible_gears
from flexgear.dynamics.model.bodies import ANGLE_PRESCRIBED, Profile
from flexgear.dynamics.lumped.planetary import parameters_from_config, planetary_system
from flexgear.dynamics.modal.system import COUPLING, PLANET, ROTATIONAL, TRANSLATIONAL, expected_multiplicity, modes
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.analysis import modal_analysis
from flexgear.dynamics.model.shafts import shaft_properties
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.errors import ConfigError
from flexgear.fe.meshing import MeshSettings, mesh_cache_dir
from flexgear.gears.geometry import GearPair
from flexgear.stiffness.loaded_mesh import loaded_mesh

SPUR = tomllib.loads(preset_path("spur_pair_flexible").read_text())
MERCURY = tomllib.loads(preset_path("mercury_1a_flexible").read_text())


def spur(shafts=False, torque=200.0, damping=None, **flexible):
    doc = copy.deepcopy(SPUR)
    doc["load"]["torque"] = torque
    if damping is not None:
        doc["contact"]["damping"] = damping
    doc["flexible"].update({"level": 1, **flexible})
    if not shafts:
        doc.pop("shafts")
    return parse_config(doc)


@pytest.fixture(scope="module")
def fe_tangent():
    """Mean over a mesh cycle of the static FE loaded mesh's tangent stiffness dF/dTE [N/m] at
    the spur pair's load (200 N m on the wheel), same level and formulation as the flexible
    model, contact outside the path included (as the model's contact search finds it): central
    difference over +-1 % of the load at every mesh position."""
    cfg = spur()
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    F = 200.0 / g2.rb
    te = [loaded_mesh(GearPair(g1, g2), F * f, settings=MeshSettings(level=1), material=cfg.material,
                      formulation=cfg.flexible["formulation"], cache_dir=mesh_cache_dir(), extended=True).te
          for f in (0.99, 1.01)]
    return float(np.mean(0.02 * F / (te[1] - te[0])))


def flank_relief(cfg, name):
    """Static FE flank displacement of gear ``name`` at its pitch radius per unit acceleration of
    its frame, bore held (:func:`conftest.inertia_load_deflection`): |u| per rad/s^2 of turning and
    per m/s^2 along the flank normal (the x, y part is along the normal, by reciprocity) [m s^2]."""
    from conftest import inertia_load_deflection

    red = reduce_flexible_gears(cfg)[name]
    g = cfg.gears[name]
    u = inertia_load_deflection(red)(0, 1, 0.5 * g.module * g.z)
    return abs(u[2]), float(np.hypot(u[0], u[1]))


def relief(cfg, name, J):
    """Compliance [m/N] a free gear's own inertia load takes off the mesh: a mesh force F turns it
    with F r_b / J, whose d'Alembert load bends its flank back towards the mate by ``|u_theta| F
    r_b / J`` (:func:`flank_relief`)."""
    return flank_relief(cfg, name)[0] * cfg.gears[name].rb / J


def test_flexible_spur_torsional_mode_is_the_fe_mesh_stiffness_formula(fe_tangent):
    """Pure pair (no shafts). Pinion prescribed (as simulated): one coordinate, f = (1/2 pi)
    sqrt(r_b2^2 / (J_2 c)); pinion free (``free_drive``): a rigid rotation at 0 Hz and f = (1/2
    pi) sqrt((r_b1^2 / J_1 + r_b2^2 / J_2) / c); c = 1 / k_m less what each free gear's own inertia
    load takes off (:func:`relief`: the rim of a gear the mesh accelerates lags its bore; 7.3 %
    of 1 / k_m for the pinion, 5.2 % for the wheel), k_m the FE tangent (fixture). Within 2 % (measured 0.2 % and
    0.6 %: the linearisation's mesh stiffness is the joint contact tangent at its equilibria, the
    FE's the load derivative of the static TE); the formula without the relief is 2.9 % and
    7.6 % below the model."""
    cfg = spur()
    m = build_model(cfg)
    J = {b.name: b.inertia for b in m.bodies}
    rb1, rb2 = cfg.gears["pinion"].rb, cfg.gears["wheel"].rb
    c1, c2 = relief(cfg, "pinion", J["pinion"]), relief(cfg, "wheel", J["wheel"])
    held = linearise(m, condensation="static")
    assert held.dofs == ["wheel.theta"]
    assert held.attrs["mesh_stiffness"]["pinion-wheel"] == pytest.approx(fe_tangent, rel=0.02)
    f = modes(held).frequencies
    c = 1.0 / fe_tangent - c2
    assert f[0] == pytest.approx(math.sqrt(rb2**2 / (J["wheel"] * c)) / (2 * math.pi), rel=0.02)
    free = modes(linearise(m, free_drive=True, condensation="static"))
    assert free.frequencies[0] == 0.0
    f2 = math.sqrt((rb1**2 / J["pinion"] + rb2**2 / J["wheel"]) / (c - c1)) / (2 * math.pi)
    assert free.frequencies[1] == pytest.approx(f2, rel=0.02)
    assert free.strain_energy["pinion-wheel"][1] == pytest.approx(1.0, abs=0.02)


def test_flexible_spur_with_shafts_matches_a_hand_built_chain(fe_tangent):
    """Motor (held) - input shaft k_t1 - pinion - mesh k_m - wheel - output shaft k_t2 - load;
    both gears on their shafts' lateral stiffness k_lat. Hand-built from shafts.py's
    properties, the gears' mass properties and the FE tangent: coordinates theta_1, theta_2,
    theta_L and each gear's centre along and across the line of action (the bearings are
    isotropic, so the line's direction does not matter); the mesh deflection r_b1 theta_1 +
    r_b2 theta_2 + u_1 - u_2 less the flanks' displacement under each gear's own inertia load,
    ``r . q''`` (:func:`flank_relief`), which adds ``-k_m (g r^T + r g^T) / 2`` to the mass.
    Every mode within 2 % (without the relief the mesh mode is 9 % above the chain's)."""
    cfg = spur(shafts=True)
    lin = linearise(build_model(cfg), condensation="static")
    f_model = modes(lin).frequencies
    pi_, po = shaft_properties(cfg, "input"), shaft_properties(cfg, "output")
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    (m1, J1), (m2, J2) = g1.mass_properties(cfg.material.rho), g2.mass_properties(cfg.material.rho)
    m1, J1 = m1 + pi_.bending_mass, J1 + pi_.gear_inertia
    m2, J2 = m2 + po.bending_mass, J2 + po.gear_inertia
    JL = po.load_inertia + po.end_inertia
    # q = theta_1, theta_2, theta_L, u1 (along), v1 (across), u2, v2
    M = np.diag([J1, J2, JL, m1, m1, m2, m2])
    g = np.array([g1.rb, g2.rb, 0, 1, 0, -1, 0])
    d2 = np.array([0, 1, -1, 0, 0, 0, 0])
    K = fe_tangent * np.outer(g, g) + po.torsional_stiffness * np.outer(d2, d2)
    K[0, 0] += pi_.torsional_stiffness
    for i, k in ((3, pi_.lateral_stiffness), (4, pi_.lateral_stiffness), (5, po.lateral_stiffness),
                 (6, po.lateral_stiffness)):
        K[i, i] += k
    (t1, n1), (t2, n2) = flank_relief(cfg, "pinion"), flank_relief(cfg, "wheel")
    r = np.array([t1, t2, 0, n1, 0, -n2, 0])
    M -= 0.5 * fe_tangent * (np.outer(g, r) + np.outer(r, g))
    import scipy.linalg
    f_hand = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)) / (2 * math.pi)
    assert len(f_model) == len(f_hand) == 7
    np.testing.assert_allclose(f_model, f_hand, rtol=0.02)


def _held(model):
    """The model with every speed zero and the driven body held at its initial angle (the
    loads constant): a free vibration about a static equilibrium."""
    m = copy.deepcopy(model)
    for b in m.bodies:
        b.omega0 = 0.0
        b.torque_ramp = 0.0
        if b.rotation == ANGLE_PRESCRIBED:
            b.speed = Profile.make(0.0)
        if b.torque is not None:
            b.torque = Profile.make(float(b.torque(1.0)))
    return m


def test_soft_gear_mode_is_the_free_vibration_frequency():
    """Pinion with the modulus scaled by 0.01 (first clamped mode 3.1 kHz) as modal coordinates,
    wheel condensed, 2 N m (the deflections of the real pinion at 200 N m), no mesh damping (the
    linearisation is undamped; the preset's mesh damper overdamps this soft mesh and moves the
    peak by 1.7 %): the linearisation at one position has a mode with most of its
    strain energy in the pinion's first mode, coupled to the mesh (its frequency is not the
    clamped one). A free vibration of the same model about that equilibrium (drive held,
    constant load, alpha = 0, h = 5 us, 40 ms), started along the mode's shape with 1e-3 of the
    static modal coordinate, oscillates at the frequency of its FFT peak (parabolic interpolation
    of the log spectrum, Hann window), corrected for the trapezoidal rule's period error: equal
    within 1 %."""
    cfg = spur(gears=["pinion"], formulation="plane_stress", modulus_scale=0.01, cutoff=10e3, dynamic_cutoff=5e3,
               torque=2.0, damping=0.0)
    model = build_model(cfg)
    assert model.modal_coordinates()
    lin = linearise(model, n_positions=1, condensation="static")
    res = modes(lin)
    f1 = model.flex[0].frequencies[0]
    i = max(range(lin.n), key=lambda k: res.strain_energy[f"pinion mode 1 ({f1:.0f} Hz)"][k])
    f_lin = res.frequencies[i]
    assert abs(f_lin / f1 - 1) > 0.02  # coupled: not the clamped frequency
    m = _held(model)
    q_eq = lin.attrs["q"]
    c0 = model.modal_coordinates()[0][1]
    q = q_eq + 1e-3 * abs(q_eq[c0]) * res.shapes[:, i] / abs(res.shapes[c0, i])
    h = 5e-6
    # the linearisation condenses the modes above dynamic_cutoff statically; so does the
    # integrator here (integrated, the 5-10 kHz condensed modes, which the step resolves, join the
    # vibration)
    r = simulate(m, 0.04, h, 1, alpha=0.0, q0=q, v0=np.zeros_like(q), condensation="static")
    x = r.modal[:, 0] - r.modal[:, 0].mean()
    n = x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(n), 16 * n))
    k = int(np.argmax(spec))
    a, b, c = np.log(spec[k - 1:k + 2])
    f_peak = (k + 0.5 * (a - c) / (a - 2 * b + c)) / (16 * n * h)
    w = 2 * math.pi * f_lin
    assert f_peak == pytest.approx(2 * math.atan(w * h / 2) / (2 * math.pi * h), rel=0.01)


@pytest.fixture(scope="module")
def mercury():
    """MERCURY 1-A flexible at level 0 without shafts, the sun on a bearing (2e7 N/m, so that a
    central member translates), the sun's rotation held by the drive."""
    doc = copy.deepcopy(MERCURY)
    doc["flexible"]["level"] = 0
    doc.pop("shafts")
    doc["supports"]["sun"] = {"stiffness": 2e7, "damping": 100.0}
    cfg = parse_config(doc)
    return cfg, linearise(build_model(cfg), condensation="static")


def test_flexible_mercury_has_lin_parker_mode_types(mercury):
    cfg, lin = mercury
    res = modes(lin)
    assert lin.has_central_translation()
    N = len(lin.planets)
    assert N == 3
    assert set(res.mode_type) <= {ROTATIONAL, TRANSLATIONAL, PLANET}
    assert min(res.type_purity) > 1 - 1e-6
    for t, mult in zip(res.mode_type, res.multiplicity):
        assert mult == expected_multiplicity(t, N, True)
    assert res.mode_type.count(TRANSLATIONAL) == 4 and res.mode_type.count(ROTATIONAL) == 2


def test_flexible_mercury_against_lin_parker(mercury):
    """Lin & Parker's lumped model (:mod:`flexgear.dynamics.lumped.planetary`) with the same masses,
    inertias, base radii, pressure angles, supports and the flexible model's mesh stiffnesses
    (each mesh's own stiffness, the other meshes held): its springs alone give Lin & Parker's
    frequencies (1e-5: the directions at the loaded equilibrium against the nominal ones) with
    the rigid-body masses (the flanks' deflection under the gears' own inertia load, which
    Lin & Parker's rigid gears lack, taken out of the mass), and the full tangent, with the
    contact coupling between meshes through the gear rims (sun-planet meshes -3.2 % of their
    stiffness each, a planet's two meshes +1.0 %), moves them by up to 1.7 % (within 3 %). The
    inertia load only raises them (every mode), most the mesh modes at 13-14 kHz (+6 to +8 %)."""
    cfg, lin = mercury
    ks = lin.attrs["mesh_stiffness"]
    lp = modes(planetary_system(parameters_from_config(cfg, ks["sun-planet1"], ks["planet1-ring"]))).frequencies
    rigid_mass = lin.mass - lin.attrs["inertia_relief_mass"]
    springs_only = copy.copy(lin)
    springs_only.stiffness = None
    springs_only.mass = rigid_mass
    np.testing.assert_allclose(modes(springs_only).frequencies, lp, rtol=1e-5)
    coupled = copy.copy(lin)
    coupled.mass = rigid_mass
    np.testing.assert_allclose(modes(coupled).frequencies, lp, rtol=0.03)
    full = modes(lin).frequencies
    assert np.all(full >= modes(coupled).frequencies * (1 - 1e-9))
    assert np.max(full / modes(coupled).frequencies) < 1.1
    S = lin.attrs["mesh_coupling"]["stiffness"]
    assert np.all(S[:3, :3][~np.eye(3, dtype=bool)] < 0)  # the sun's rim: a loaded sun mesh unloads the others
    assert lin.attrs["mesh_fit_residual"] < 0.01


def test_energy_fractions_of_a_flexible_model_sum_to_one(mercury):
    _, lin = mercury
    res = modes(lin)
    total = sum(v for v in res.strain_energy.values())
    np.testing.assert_allclose(total, 1.0, atol=1e-9)
    assert np.all(np.abs(res.strain_energy[COUPLING]) < 0.2)
    np.testing.assert_allclose(sum(res.kinetic_energy.values()), 1.0, atol=1e-9)


def test_flexible_model_without_load_is_an_error():
    doc = copy.deepcopy(SPUR)
    doc["flexible"]["level"] = 1
    doc.pop("shafts")
    doc["load"]["torque"] = 0.0
    with pytest.raises(ConfigError, match="load.torque"):
        modal_analysis(parse_config(doc))


def test_cli_modal_of_a_flexible_configuration(tmp_path):
    from flexgear.app.cli import main

    doc = (preset_path("spur_pair_flexible").read_text().replace("level = 2 ", "level = 1 "))
    path = tmp_path / "flex.toml"
    path.write_text(doc)
    out = tmp_path / "modal"
    assert main(["modal", str(path), "-o", str(out), "--positions", "4"]) == 0
    text = (out / "modes.md").read_text()
    assert "flexible model linearised" in text and "pinion-wheel" in text and "input shaft torsion" in text
    assert "Stiffness between meshes" in text
    # the preset integrates its condensed modes; the analysis says so and follows it
    assert "Condensed modes: the 101 condensed gear modes integrated" in text and "pinion.eta101" not in text
    assert "pinion.eta54" in text and "wheel.eta47" in text
    assert json.loads((out / "modes.json").read_text())["condensation"]["mode"] == "integrated"
    static = tmp_path / "static.toml"
    static.write_text(doc.replace('condensation = "integrated"', 'condensation = "static"'))
    assert main(["modal", str(static), "-o", str(tmp_path / "s"), "--positions", "4"]) == 0
    text = (tmp_path / "s" / "modes.md").read_text()
    assert "condensed quasi-statically (condensation = 'static')" in text and ".eta" not in text


def test_non_conservative_tangent_is_refused(monkeypatch):
    """A tangent stiffness that is not symmetric (forces not derivable from a potential at the
    operating point) has no modal analysis: an error, not symmetrised silently."""
    from flexgear.dynamics.integrator.simulation import evaluate as original
    from flexgear.dynamics.modal import equilibrium, linearise as linearisation, tangent

    def skewed(model, q, v, t=0.0, **kw):
        ev = original(model, q, v, t, **kw)
        Kt = ev["Kt"].copy()
        i, j = np.unravel_index(np.argmax(np.abs(Kt - np.diag(np.diag(Kt)))), Kt.shape)
        Kt[i, j] *= 1.01  # a 1 % skew of the largest coupling term (Newton still converges with it)
        return dict(ev, Kt=Kt)

    model = build_model(spur(shafts=True))
    for module in (equilibrium, linearisation, tangent):  # every module of the linearisation that evaluates
        monkeypatch.setattr(module, "evaluate", skewed)
    for condensation in ("static", "integrated"):  # integrated: relative to the diagonal, not to omega^2 of the modes
        with pytest.raises(ConfigError, match="not symmetric"):
            linearise(model, n_positions=2, condensation=condensation)


def _prony_frequency(x, h, n=400):
    """Frequency [Hz] of the oscillating root of a third-order linear recurrence x[k+3] = a x[k+2]
    + b x[k+1] + c x[k] + d fitted to the first n samples (the HHT-alpha step of one mode is
    exactly such a recurrence: two complex roots and a spurious real one; d takes the
    equilibrium offset), so a mode that the scheme damps out in a few periods is still
    measured exactly."""
    x = np.asarray(x[:n], float)
    A = np.column_stack([x[2:-1], x[1:-2], x[:-3], np.ones(len(x) - 3)])
    a, b, c, _ = np.linalg.lstsq(A, x[3:], rcond=None)[0]
    z = np.roots([1.0, -a, -b, -c])
    z = z[np.argmax(np.abs(z.imag))]
    return abs(np.angle(z)) / (2 * math.pi * h)


def test_integrated_frequency_is_what_the_solver_makes_of_a_mode(undamped_spur):
    """The HHT-alpha period error. alpha = 0 gives the trapezoidal rule's closed form (2 / h)
    atan(omega h / 2). The flexible spur pair with shafts, undamped, released from its
    equilibrium along its highest mode (the mesh mode, 16.8 kHz at this position) by 0.1 um of
    mesh deflection: with h = 25 us it oscillates at ``integrated_frequency`` of the linearised
    frequency (alpha = 0 and -0.1; 30 and 32 % below the mode itself), and with h = 5 us, alpha =
    0, 2.2 % below it: each within 0.5 % (measured 3.2e-4, 2.7e-4, 5.9e-4; the linearisation
    carries the flanks' deflection under the gears' own inertia load as a symmetrised mass, the
    integrator as it comes; without it in the mass the difference was 5 %). The linearisation
    condenses the modes statically, so the integrator does too here (``condensation="static"``;
    integrated, the 43-64 kHz gear modes add their inertia: 11.86 instead of 11.71 kHz at 5 us).
    Undamped with alpha = 0 the free vibration keeps its amplitude."""
    from flexgear.dynamics.modal.analysis import integrated_frequency

    f = np.array([100.0, 3e3, 9e3])
    w = 2 * math.pi * f
    h = 25e-6
    np.testing.assert_allclose(integrated_frequency(f, h, 0.0), np.arctan(w * h / 2) / (math.pi * h), rtol=1e-12)
    assert integrated_frequency(9e3, h, -0.1) < integrated_frequency(9e3, h, 0.0)
    with pytest.raises(ConfigError, match="alpha"):
        integrated_frequency(9e3, h, -0.5)
    model, lins = undamped_spur
    lin = lins["static"]
    res = modes(lin)
    i = lin.n - 1
    phi = res.shapes[:, i]
    q = lin.attrs["q"] + 1e-7 * phi / np.abs(res.system.springs[-1].g @ phi)  # 0.1 um of mesh deflection
    for h, alpha in ((25e-6, 0.0), (25e-6, -0.1), (5e-6, 0.0)):
        r = simulate(_held(model), 400 * h, h, 1, alpha=alpha, q0=q, v0=np.zeros_like(q), condensation="static")
        expected = integrated_frequency(res.frequencies[i], h, alpha)
        assert _prony_frequency(r.records.mesh_force[:, 0], h) == pytest.approx(expected, rel=5e-3)
        if h == 25e-6:
            assert expected < 0.75 * res.frequencies[i]
    # undamped, alpha = 0: the amplitude stays (the inertia load's coupling pumps no energy):
    # over 670 periods within 1e-3 (measured 2e-4). (Integrated, the linearisation's shape is not
    # quite a mode of the integrator's model, so the amplitude beats by a few per cent; the
    # integrated modes' energy is that of modal coordinates, tests/test_condensed.py and the free
    # vibration of tests/test_flexible_modes.py.)
    r = simulate(_held(model), 8000 * 5e-6, 5e-6, 1, alpha=0.0, q0=q, v0=np.zeros_like(q), condensation="static")
    F = r.records.mesh_force[:, 0] - np.median(r.records.mesh_force[:, 0])
    first, last = np.abs(F[:800]).max(), np.abs(F[-800:]).max()
    assert abs(last / first - 1) < 1e-3


def test_inertia_relief_keeps_the_integrators_mass_reciprocal():
    """The condensed modes' deflection under the gears' own inertia load makes the contact
    forces depend on the accelerations: a mass ``X = -dQ/dq''`` that is not symmetric between
    bodies (a gear's flank relief against its mate's acceleration). Taken as it comes, it splits
    MERCURY 1-A's pairs of equal frequencies into growing and decaying oscillations (complex
    eigenvalues; at level 1 pairs at 6.8 and 16.2 kHz with a growth time of 3.4 ms, seen as a
    16 kHz oscillation building up in runs at steps of 3 us). The integrator's Newton matrix
    mass, Mq plus X at the step's ``d q''/dq`` (here 1), is symmetric (the kernel adds the
    antisymmetric part, :func:`flexgear.dynamics.flexible.compliant.relief_reciprocity`), so every
    frequency of the linearised model is real, the same as the modal analysis's."""
    import scipy.linalg

    from flexgear.dynamics.integrator.simulation import evaluate

    doc = copy.deepcopy(MERCURY)
    doc["flexible"]["level"] = 0  # with its shafts: the sun and carrier translate (pairs of modes)
    model = build_model(parse_config(doc))
    lin = linearise(model, n_positions=1, condensation="static")
    held, q, zero = _held(model), lin.attrs["q"], np.zeros_like(lin.attrs["q"])
    e0 = evaluate(held, q, zero)
    e1 = evaluate(held, q, zero, acceleration_slope=1.0)
    X = e1["Kt"] - e0["Kt"]
    K = 0.5 * (e0["Kt"] + e0["Kt"].T)
    assert np.abs(X - X.T).max() > 0.1 * np.abs(X).max()  # the relief's mass is unsymmetric
    w_raw = scipy.linalg.eigvals(K, e0["Mq"] + X)
    assert np.max(np.abs(np.sqrt(w_raw.astype(complex)).imag)) > 2 * math.pi * 1.0  # a growing pair
    M = e1["Mq"] + X  # what the integrator's Newton matrix carries as mass
    assert np.abs(M - M.T).max() < 1e-6 * np.abs(M).max()
    w = scipy.linalg.eigvals(K, M)
    assert np.all(np.abs(w.imag) <= 1e-9 * np.abs(w.real).max())
    # the modal analysis's frequencies (it averages the three planets' meshes, which at one raw
    # pose differ by ~1e-4: the pairs split by that much here)
    np.testing.assert_allclose(np.sort(np.sqrt(np.abs(w.real))) / (2 * math.pi), modes(lin).frequencies, rtol=2e-4)


# ---------------------------------------------------------------------------------------------
# condensation = "integrated": the condensed modes carry their own inertia, as coordinates
# ---------------------------------------------------------------------------------------------


def _peaks(x, h, pad=16):
    """Spectral peaks of x (sampled every h [s]): (frequency [Hz], amplitude relative to the
    largest), largest first; Hann window, parabolic interpolation of the log spectrum."""
    x = np.asarray(x, float) - np.mean(x)
    n = x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(n), pad * n))
    ks = [k for k in range(1, spec.size - 1) if spec[k] > spec[k - 1] and spec[k] >= spec[k + 1]]
    ks.sort(key=lambda k: -spec[k])
    out = []
    for k in ks:
        a, b, c = np.log(spec[k - 1:k + 2])
        out.append(((k + 0.5 * (a - c) / (a - 2 * b + c)) / (pad * n * h), spec[k] / spec[ks[0]]))
    return out


def _release(model, lin, i, size):
    """Initial coordinates of a free vibration: the equilibrium plus mode i's shape in the
    integrator's coordinates (the rigid ones and the model's own modal coordinates; condensed
    modes start at their static response), scaled to ``size`` in its largest rigid entry."""
    n0 = len(model.initial_state()[0])
    phi = modes(lin).shapes[:, i]
    return lin.attrs["q"][:n0] + size * phi[:n0] / np.abs(phi[:model.rigid_coordinates()]).max()


def test_linearisation_condensation_is_checked():
    with pytest.raises(ConfigError, match="condensation"):
        linearise(build_model(spur(gears=["pinion"], formulation="plane_stress", modulus_scale=0.01, cutoff=10e3)),
                  condensation="quasi-static")


def test_integrated_condensation_linearises_every_mode_as_a_coordinate():
    """``condensation = "integrated"`` is the same linear system as the reduction built with
    every mode a coordinate (``dynamic_cutoff = cutoff``, the reduced model's modal mass and
    stiffness taken from the reduction, not from the condensed tables): frequencies within
    1e-9 (measured 1e-12), also from a model that has some modes as coordinates already. The
    soft pinion (modulus x 0.01, clamped modes 3.1-9.8 kHz, all condensed) shows what the
    static condensation leaves out: its one mode (1.66 kHz) becomes the coupled mesh-gear mode
    at 1.55 kHz, 6 % lower, and the pinion's own modes appear."""
    kw = dict(gears=["pinion"], formulation="plane_stress", modulus_scale=0.01, cutoff=10e3, torque=2.0, damping=0.0)
    condensed = build_model(spur(dynamic_cutoff=0.0, **kw))
    some = build_model(spur(dynamic_cutoff=5e3, **kw))
    every = build_model(spur(dynamic_cutoff=10e3, **kw))
    assert not condensed.modal_coordinates() and every.flex[0].shape.shape[3] == 0
    reference = modes(linearise(every, n_positions=1))
    for model in (condensed, some):
        lin = linearise(model, n_positions=1)
        assert lin.dofs == reference.system.dofs
        assert lin.attrs["condensation"] == "integrated"
        np.testing.assert_allclose(modes(lin).frequencies, reference.frequencies, rtol=1e-9)
        np.testing.assert_allclose(lin.K, reference.system.K, rtol=0, atol=1e-9 * np.abs(lin.K).max())
        np.testing.assert_allclose(lin.M, reference.system.M, rtol=0, atol=1e-9 * np.abs(lin.M).max())
    static = modes(linearise(condensed, n_positions=1, condensation="static")).frequencies
    assert len(static) == 1 and static[0] / reference.frequencies[0] > 1.05


def test_soft_gear_integrated_modes_against_the_integrator():
    """The soft pinion of the test above with every mode condensed, released from its
    equilibrium by a turn of the wheel (the only rigid coordinate; the integrator starts the
    condensed modes at their static response): with the default
    (integrated) condensation the mesh force rings at ``integrated_frequency`` (h = 5 us,
    alpha = 0) of the integrated linearisation's mode that the release excites most in the
    mesh (the coupled mode, 1.55 kHz), with static condensation at the static linearisation's
    (1.66 kHz); each within 1 % (measured 2e-4 and 3e-4), and the two 6 % apart."""
    from flexgear.dynamics.modal.analysis import integrated_frequency

    model = build_model(spur(gears=["pinion"], formulation="plane_stress", modulus_scale=0.01, cutoff=10e3,
                             dynamic_cutoff=0.0, torque=2.0, damping=0.0))
    h = 5e-6
    found = {}
    for condensation in ("integrated", "static"):
        lin = linearise(model, n_positions=1, condensation=condensation)
        res = modes(lin)
        mesh = next(s for s in lin.springs if s.kind == "mesh")
        # the release: a unit turn of the wheel, the condensed modes at their static response
        x0 = np.zeros(lin.n)
        x0[0] = 1.0
        x0[1:] = -np.linalg.solve(lin.K[1:, 1:], lin.K[1:, 0]) if lin.n > 1 else 0.0
        # its part in each mode times the mode's mesh deflection
        share = np.abs((res.shapes.T @ lin.M @ x0) * (mesh.g @ res.shapes))
        f = res.frequencies[int(np.argmax(share))]
        q = lin.attrs["q"][:1] + 1e-6
        r = simulate(_held(model), 0.04, h, 1, alpha=0.0, q0=q, v0=np.zeros(1), condensation=condensation)
        peak = _peaks(r.records.mesh_force[:, 0], h)[0][0]
        assert peak == pytest.approx(integrated_frequency(f, h, 0.0), rel=0.01)
        found[condensation] = f
    assert found["static"] / found["integrated"] > 1.05


def _undamped(preset_doc, level):
    """The flexible model of a preset document at an FE mesh level, without contact or shaft
    damping."""
    doc = copy.deepcopy(preset_doc)
    doc["flexible"]["level"] = level
    doc["contact"]["damping"] = 0.0
    for k in ("input", "output"):
        doc["shafts"][k]["damping_ratio"] = 0.0
    return build_model(parse_config(doc))


@pytest.fixture(scope="module")
def undamped_spur():
    """The flexible spur pair (level 1, shafts) without damping, and its linearisations with
    the condensed modes integrated and static at one position."""
    model = _undamped(SPUR, level=1)
    return model, {c: linearise(model, n_positions=1, condensation=c) for c in ("integrated", "static")}


def test_integrated_linearisation_is_the_integrators_mesh_mode(undamped_spur):
    """The flexible spur pair's mesh mode (most mesh strain energy), linearised with the
    preset's integrated condensation, against a free vibration of the integrator with its
    default condensation, released from the equilibrium along the mode's rigid part (h = 5 us,
    alpha = 0, 40 ms): the mesh force's largest peak at ``integrated_frequency`` within 0.5 %
    (the bound of the static test above; measured 6e-5). The static linearisation's mode
    (1.6 % lower) misses it by more than 1 %: the gear modes' own inertia is in the
    integrator and in this linearisation, not in the static one."""
    from flexgear.dynamics.modal.analysis import integrated_frequency

    model, lin = undamped_spur
    h = 5e-6
    f = {}
    for c, sysl in lin.items():
        res = modes(sysl)
        i = int(np.argmax(res.strain_energy["pinion-wheel"]))
        f[c] = integrated_frequency(res.frequencies[i], h, 0.0)
        if c == "integrated":
            q = _release(model, sysl, i, 1e-6)
    r = simulate(_held(model), 8000 * h, h, 1, alpha=0.0, q0=q, v0=np.zeros_like(q))
    peak = _peaks(r.records.mesh_force[:, 0], h)[0][0]
    assert peak == pytest.approx(f["integrated"], rel=5e-3)
    assert abs(peak / f["static"] - 1) > 0.01


def test_integrated_planetary_keeps_its_mode_types_and_the_integrators_frequencies():
    """MERCURY 1-A flexible at level 0 with its shafts, undamped, condensed modes integrated:
    every gear mode a coordinate (sun 54, planets 47, ring 161). The central members' modes
    turn into combinations of each other under the planets' rotation (:func:`modal_rotation`;
    taken as unchanged, the cyclic mean put the translational mesh pair at 8.1 instead of 6.8
    kHz): with the turn every mode below 20 kHz is rotational or translational with Lin &
    Parker's multiplicity, and released along the first translational mesh pair (6.83 kHz) and
    the rotational mesh mode (9.72 kHz) the integrator rings at their ``integrated_frequency``
    (h = 5 us, alpha = 0, 20 ms) within 0.1 % (measured 3e-5 and 1e-4; statically condensed they
    are 0.5 % and 0.4 % lower)."""
    from flexgear.dynamics.modal.analysis import integrated_frequency
    from flexgear.dynamics.modal.system import modal_rotation
    from flexgear.dynamics.modal.linearise import modes_as_coordinates

    model = _undamped(MERCURY, level=0)
    for fb in modes_as_coordinates(model).flex:
        if model.bodies[fb.body].attrs.get("role") == "planet":  # planets map to each other
            continue
        T = modal_rotation(fb, 3)
        np.testing.assert_allclose(T.T @ T, np.eye(fb.modes), atol=1e-9)
        np.testing.assert_allclose(T @ T @ T, np.eye(fb.modes), atol=1e-9)
    lin = linearise(model, n_positions=1)
    assert sorted(lin.modal_rotation) == ["ring", "sun"]
    assert lin.attrs["planet_asymmetry"] < 1e-2
    res = modes(lin)
    low = res.frequencies < 20e3
    assert min(res.type_purity[low]) > 1 - 1e-6
    for t, mult in zip(np.array(res.mode_type)[low], res.multiplicity[low]):
        assert mult == expected_multiplicity(t, 3, True)
    h = 5e-6
    for kind, band in ((TRANSLATIONAL, (5e3, 8e3)), (ROTATIONAL, (8e3, 12e3))):
        i = next(k for k in range(lin.n) if res.mode_type[k] == kind and band[0] < res.frequencies[k] < band[1])
        q = _release(model, lin, i, 1e-7)
        r = simulate(_held(model), 4000 * h, h, 1, alpha=0.0, q0=q, v0=np.zeros_like(q))
        peaks = [f for f, a in _peaks(r.records.mesh_force[:, 0], h)[:6] if a > 0.1]
        expected = integrated_frequency(res.frequencies[i], h, 0.0)
        assert min(abs(p / expected - 1) for p in peaks) < 1e-3


def test_integrated_cycle_mean_keeps_the_quasi_static_mesh_stiffness():
    """Over a mesh cycle the contact moves along the flanks and to the next tooth: the mean of
    K with the modes as coordinates spreads their contact coupling, and its static condensation
    is stiffer than the mean mesh stiffness (the Schur complement is concave in K). The
    linearisation corrects the rigid block, so that at 8 positions the static condensation of
    the integrated system's K is the static linearisation's K (1e-6 of its largest entry,
    measured 3e-12; the static mass carries the inertia relief instead), and the shaft mode
    (95 Hz, where the gear modes answer statically) is the same in both within 1e-4 (measured
    2e-6; uncorrected it was 0.5 % higher, and the mesh mode 5.7 % above the static one
    instead of 2.1 %)."""
    doc = copy.deepcopy(SPUR)
    doc["flexible"]["level"] = 1
    model = build_model(parse_config(doc))
    lin = {c: linearise(model, n_positions=8, condensation=c) for c in ("integrated", "static")}
    K = lin["integrated"].K
    r = model.rigid_coordinates()  # the modal coordinates follow the rigid ones
    S = K[:r, :r] - K[:r, r:] @ np.linalg.solve(K[r:, r:], K[r:, :r])
    np.testing.assert_allclose(S, lin["static"].K, rtol=0, atol=1e-6 * np.abs(lin["static"].K).max())
    f = {c: modes(s).frequencies for c, s in lin.items()}
    assert f["integrated"][0] == pytest.approx(f["static"][0], rel=1e-4)


def test_flexible_report_gives_the_effective_mesh_stiffness(fe_tangent, tmp_path):
    """With the condensed modes integrated (the presets' default) the spring the linearisation
    puts on the mesh is only the contact between the reduced flanks, the gears' compliance being
    in their modes (about 5 times the FE mesh stiffness here). The effective mesh stiffness, the
    modes condensed statically, is the static FE loaded mesh's tangent dF/dTE (fixture; an
    independent solve of the pair's influence coefficients and Hertz contact) within 2 % (as
    the static linearisation's, test above; measured 0.14 % at the default 24 positions, 2.4 %
    at 8: the cycle's two-pair stretch is sampled coarsely), and it is the mesh stiffness of the
    linearisation with the modes condensed in the reduction's flank tables instead (1e-6,
    measured 1e-12); the report names both. Before: only the contact spring, 1.91e9 N/m,
    tabled as the "mean tangent stiffness"."""
    from flexgear.dynamics.modal.analysis import write_modal_outputs

    model = build_model(spur())
    lin = linearise(model)
    assert lin.attrs["condensation"] == "integrated" and lin.body_modes
    k_eff = lin.attrs["effective_mesh_stiffness"]["pinion-wheel"]
    assert k_eff == pytest.approx(fe_tangent, rel=0.02)
    static = linearise(model, condensation="static").attrs["mesh_stiffness"]["pinion-wheel"]
    assert k_eff == pytest.approx(static, rel=1e-6)
    assert lin.attrs["mesh_stiffness"]["pinion-wheel"] > 2 * fe_tangent  # the contact spring alone
    write_modal_outputs(modes(lin), tmp_path)
    text = (tmp_path / "modes.md").read_text()
    assert "effective mesh stiffness N/m" in text and "contact spring between reduced flanks N/m" in text
    assert "mean tangent stiffness" not in text
    data = json.loads((tmp_path / "modes.json").read_text())
    assert data["effective_mesh_stiffness"]["pinion-wheel"] == pytest.approx(k_eff)
    assert "modal coordinates held" in data["units"]["mesh_stiffness"]
