"""Linearised modal analysis of the rigid model: eigen checks, mode types, stiffness, bad input."""
import copy
import dataclasses
import math
import warnings

import numpy as np
import pytest

from flexgear.app.cli import main
from flexgear.config import load_config, loads_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.bodies import Profile
from flexgear.dynamics.modal.system import PLANET, ROTATIONAL, TRANSLATIONAL, expected_multiplicity, modes
from flexgear.dynamics.modal.analysis import modal_analysis
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.integrator.simulation import evaluate
from flexgear.errors import ConfigError

MERCURY = preset_path("mercury_1a").read_text()
ELASTIC = (MERCURY.replace('planets = "revolute"  #', 'planets = {stiffness = 1e8}  #')
           .replace('sun = "revolute"      #', 'sun = {stiffness = 1e8}  #'))


def _model(text):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_model(loads_config(text))


@pytest.fixture(scope="module")
def mercury():
    return _model(MERCURY)


@pytest.fixture(scope="module")
def elastic():
    return _model(ELASTIC)


def _check_types(res, N):
    translate = res.system.has_central_translation()
    assert np.all(res.type_purity > 1 - 1e-6)
    for i, t in enumerate(res.mode_type):
        assert res.multiplicity[i] == expected_multiplicity(t, N, translate), (i, t, res.frequencies[i])


def test_shapes_are_mass_normalised_and_orthogonal(elastic):
    res = modes(linearise(elastic, n_positions=6))
    M, K, Phi = res.system.M, res.system.K, res.shapes
    assert np.allclose(Phi.T @ M @ Phi, np.eye(len(Phi)), atol=1e-9)
    D = Phi.T @ K @ Phi
    assert np.allclose(D, np.diag(res.eigenvalues), atol=1e-7 * res.eigenvalues.max())
    for i in range(len(res.frequencies)):  # energies are fractions
        assert sum(v[i] for v in res.kinetic_energy.values()) == pytest.approx(1.0)
        assert sum(v[i] for v in res.strain_energy.values()) == pytest.approx(1.0)


def test_spring_stiffness_equals_the_solver_tangent(mercury):
    """With one position, the linear system is the solver's own tangent at the equilibrium."""
    sysl = linearise(mercury, n_positions=1)
    q = sysl.attrs["q"]
    held = copy.copy(mercury)  # the sun held still (no contact damping from its speed)
    held.bodies = [dataclasses.replace(b, speed=Profile.make(0.0)) if b.speed is not None else b
                   for b in mercury.bodies]
    ev = evaluate(held, q, np.zeros_like(q))
    # (one line of action per mesh: the contacts of a mesh share their direction to ~1e-6)
    assert np.allclose(sysl.K, ev["Kt"], rtol=1e-6, atol=1e-6 * np.abs(ev["Kt"]).max())
    assert np.allclose(sysl.M, ev["Mq"], rtol=1e-12)
    # the equilibrium: every planet carries a third of the sun torque (60 N m carrier, ring fixed)
    zs, zr = 24, 66
    F = 60.0 / (1 + zr / zs) / 3 / (loads_config(MERCURY).gears["sun"].rb)
    for name in ("sun-planet1", "sun-planet2", "sun-planet3"):
        assert sysl.attrs["mesh_force"][name] == pytest.approx(F, rel=1e-3)  # outline normals to ~1e-4


def test_rigid_mercury_mode_types(mercury):
    """Planets on rigid pins, sun held by the drive: two rotational modes and one planet mode of
    multiplicity N - 1 = 2 (Lin & Parker's purely rotational structure), no zero mode."""
    res = modes(linearise(mercury))
    _check_types(res, 3)
    assert res.mode_type.count(ROTATIONAL) == 2 and res.mode_type.count(PLANET) == 2
    assert res.frequencies.min() > 100.0


def test_zero_mode_exactly_when_unconstrained(mercury):
    held = modes(linearise(mercury, n_positions=3))
    free = modes(linearise(mercury, n_positions=3, free_drive=True))
    assert np.count_nonzero(held.frequencies == 0.0) == 0
    assert np.count_nonzero(free.frequencies == 0.0) == 1
    assert free.mode_type[0] == ROTATIONAL
    # the rigid-body mode turns the whole train: carrier / sun = z_s / (z_s + z_r)
    dofs = free.system.dofs
    phi = free.shapes[:, 0]
    # (to the outline discretisation: contact normals and arms agree with the involute to ~1e-5)
    assert phi[dofs.index("carrier.theta")] / phi[dofs.index("sun.theta")] == pytest.approx(24 / 90, rel=1e-4)


def test_elastic_bearings_translational_modes_and_frame_invariance(elastic):
    """Elastic sun and planet bearings: rotational (1) and translational (2) modes for N = 3. The
    same set turned by 60 deg (a whole number of sun and ring pitches) has the same frequencies."""
    res = modes(linearise(elastic, n_positions=6))
    _check_types(res, 3)
    assert res.mode_type.count(TRANSLATIONAL) > 0 and PLANET not in res.mode_type
    turned = _model(ELASTIC.replace("first_planet_angle_deg = 90.0", "first_planet_angle_deg = 150.0"))
    res2 = modes(linearise(turned, n_positions=6))
    assert np.allclose(res2.frequencies, res.frequencies, rtol=1e-7)


def test_four_planets_have_a_planet_mode(tmp_path):
    """N = 4 (z_s + z_r = 90 is not divisible by 4, so 26 + 70 = 96): rotational, translational
    and planet modes with multiplicities 1, 2 and N - 3 = 1."""
    text = (ELASTIC.replace("teeth = 24", "teeth = 26").replace("teeth = 66", "teeth = 70")
            .replace("teeth = 21", "teeth = 22").replace("planets = 3", "planets = 4"))
    res = modes(linearise(_model(text), n_positions=4))
    _check_types(res, 4)
    assert res.mode_type.count(PLANET) == 3  # one planet mode per planet coordinate (x, y, theta)


def test_spur_mesh_stiffness_is_the_load_derivative():
    """Spur pair, one position: the mesh stiffness is d(load)/d(deflection) of the static
    equilibrium (torque 200 -> 201 N m), and the single mode is sqrt(k r_b^2 / J_wheel)."""
    text = preset_path("spur_pair").read_text()
    assert "torque = 200.0" in text
    s0 = linearise(_model(text), n_positions=1)
    s1 = linearise(_model(text.replace("torque = 200.0", "torque = 201.0")), n_positions=1)
    cfg = loads_config(text)
    rb = cfg.gears["wheel"].rb
    i = s0.dofs.index("wheel.theta")
    dth = abs(s1.attrs["q"][i] - s0.attrs["q"][i])
    k_fd = (1.0 / rb) / (rb * dth)
    k0, k1 = s0.attrs["mesh_stiffness"]["pinion-wheel"], s1.attrs["mesh_stiffness"]["pinion-wheel"]
    assert k_fd == pytest.approx(0.5 * (k0 + k1), rel=2e-3)
    model = _model(text)
    f = math.sqrt(k0 * rb**2 / model.bodies[1].inertia) / (2 * math.pi)
    assert modes(s0).frequencies[0] == pytest.approx(f, rel=1e-4)


def test_no_load_is_an_error_naming_the_key():
    text = MERCURY.replace("torque = 60.0", "torque = 0.0")
    with pytest.raises(ConfigError, match="load.torque"):
        linearise(_model(text))


def test_cli_modal_writes_report_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "modal"
    assert main(["modal", "mercury_1a", "-o", str(out), "--positions", "3"]) == 0
    text = (out / "modes.md").read_text()
    assert "rotational" in text and "planet" in text and "sun-planet1" in text
    assert (out / "modes.json").exists() and (out / "campbell.png").stat().st_size > 10_000
    stamp = (out / "modes.md").stat().st_mtime_ns
    assert main(["modal", "mercury_1a", "-o", str(out)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert (out / "modes.md").stat().st_mtime_ns == stamp
    (out / "modes.md").unlink()
    (out / "modes.json").unlink()
    assert main(["modal", "mercury_1a", "-o", str(out)]) == 2  # the figure alone is refused too, before any work
    assert "campbell.png' already exists" in capsys.readouterr().err and not (out / "modes.md").exists()
    # the lumped model's modes are the rigid model's linearisation: the report names both
    assert main(["modal", "mercury_1a:lumped", "-o", str(tmp_path / "lumped"), "--positions", "3"]) == 0
    assert (tmp_path / "lumped" / "modes.md").read_text().splitlines()[2].startswith("lumped model: the rigid model")


def test_the_modal_campbell_diagram_marks_the_operating_speed_and_the_modes_it_reaches():
    """``flexgear modal``'s figure: the frequency axis reaches 1.25 times the highest mode with at
    least 20 % of its strain energy in the meshes (at least 1.1 times the 4th harmonic at 1.5
    times the operating speed), the speed axis (to 1.55 times the top speed, room for the mode
    labels) the speed where the 4th harmonic gets there, at least 1.5 times the operating speed
    (the mean input frequency, a vertical line); each mode up to the top is a horizontal line in
    its type's style (a degenerate group one line), and the crossings are those of the mesh lines
    k r_m f_in with the modes; per Hz of the sun, ring held: r_m = z_s z_r / (z_s + z_r)."""
    from flexgear.results.campbell_plot import TYPE_STYLE, modal_campbell

    cfg = load_config("mercury_1a:lumped")
    res = modal_analysis(cfg, n_positions=3)
    fig, cr = modal_campbell(res, cfg)
    ax = fig.axes[0]
    assert cfg.drive["body"] == "sun"
    r_m = 24 * 66 / 90
    meshes = [s.name for s in res.system.springs if s.kind == "mesh"]
    share = sum(res.strain_energy[m] for m in meshes)
    top = 1.25 * max(f for f, e in zip(res.frequencies, share) if f > 0 and e >= 0.2)
    hi = top / (4.4 * r_m)
    assert top > 4.4 * r_m * 1.5 * cfg.input_frequency and hi > 1.5 * cfg.input_frequency
    assert ax.get_xlim()[1] == pytest.approx(1.55 * hi) and ax.get_ylim()[1] == pytest.approx(top)
    vertical = [ln for ln in ax.lines if ln.get_xdata()[0] == ln.get_xdata()[-1] and ln.get_ls() == ":"]
    assert len(vertical) == 1 and vertical[0].get_xdata()[0] == pytest.approx(cfg.input_frequency, rel=1e-12)
    shown = sorted({round(f, 6) for f in res.frequencies if 0 < f <= top})
    horizontal = [ln for ln in ax.lines if len(ln.get_ydata()) == 2 and ln.get_ydata()[0] == ln.get_ydata()[1]
                  and ln.get_xdata()[0] == 0.0 and ln.get_ydata()[0] > 0]
    assert sorted(ln.get_ydata()[0] for ln in horizontal) == pytest.approx(shown, rel=1e-9)
    for ln in horizontal:
        t = res.mode_type[int(np.argmin(np.abs(res.frequencies - ln.get_ydata()[0])))]
        assert (ln.get_color(), ln.get_ls()) == TYPE_STYLE[t]
    assert cr
    for c in cr:
        assert c.input_speed * c.harmonic * r_m == pytest.approx(c.frequency, rel=1e-12)
    fast = dataclasses.replace(cfg, drive=dict(cfg.drive, speed_hz=2.0 * hi))  # modes as linearised above
    assert modal_campbell(res, fast)[0].axes[0].get_xlim()[1] == pytest.approx(1.55 * 1.5 * fast.input_frequency)


def test_a_lumped_models_modes_take_its_mesh_stiffness_source():
    """``[lumped] mesh_stiffness`` sets the lumped mesh's springs, in its runs and in its modes
    (``flexgear modal`` reported the contact law's tangent, 7937.8 Hz, for every source, while the
    runs rang at 9307 Hz with a constant 4e8 N/m). The spur pair held at its driven pinion is one
    torsional mode, f proportional to sqrt(k): constant 4e8 N/m and the ISO 6336 mean scale the
    contact tangent's frequency by sqrt(k / k_contact); the report names the source."""
    from flexgear.stiffness.iso6336 import pair_stiffness

    base = 'model = "lumped"\n' + preset_path("spur_pair").read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        contact = modal_analysis(loads_config(base))
        constant = modal_analysis(loads_config(base + '\n[lumped]\nmesh_stiffness = "constant"\n'
                                               'constant_stiffness = {pinion-wheel = 4.0e8}\n'))
        cfg = loads_config(base + '\n[lumped]\nmesh_stiffness = "iso6336"\n')
        iso = modal_analysis(cfg)
    first = {name: float(m.frequencies[m.frequencies > 1.0][0]) for name, m in
             (("contact", contact), ("constant", constant), ("iso", iso))}
    k_contact = contact.system.attrs["mesh_stiffness"]["pinion-wheel"]
    p, w = cfg.gears["pinion"], cfg.gears["wheel"]
    k_iso = pair_stiffness(p.z, w.z, p.module, p.face_width, alpha=p.pressure_angle, x1=p.x, x2=w.x, ha=p.ha,
                           hf=p.hf).k_mesh
    assert first["constant"] == pytest.approx(first["contact"] * math.sqrt(4.0e8 / k_contact), rel=1e-9)
    assert first["iso"] == pytest.approx(first["contact"] * math.sqrt(k_iso / k_contact), rel=1e-9)
    assert iso.system.attrs["mesh_stiffness_source"] == "iso6336"


def test_a_rigid_body_mode_names_no_spring_for_its_strain_energy():
    """With the drive free the set turns as a rigid body at 0 Hz: no spring holds strain energy
    (the table read 'sun-planet1 (0 %)'); every elastic mode names its spring."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = modal_analysis(load_config("mercury_1a:lumped"), free_drive=True)
    rows, headers = m.table()
    col = headers.index("max strain energy")
    assert m.frequencies[0] < 1e-6 and rows[0][col] == "- (none: a rigid-body mode)"
    assert all(r[col].endswith("%)") for r in rows[1:])
