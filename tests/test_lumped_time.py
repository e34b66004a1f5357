"""The lumped model in the time domain (model = "lumped"): quasi-static agreement with the rigid
model, results layout, stiffness sources, backlash and contact loss, bad input."""
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path, time_grid
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.errors import ConfigError
from flexgear.results.store import load, save, validate
from flexgear.stiffness.iso6336 import pair_stiffness

MERCURY = preset_path("mercury_1a").read_text()
LUMPED = 'model = "lumped"\n' + MERCURY


def _run(text, run_in, duration):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(text)
        cfg.simulation.update(run_in=run_in, duration=duration)
        return flexgear.run(cfg)


def _twist(res):
    """Carrier angle behind the kinematic position [rad] (static transmission error)."""
    return res.bodies["carrier"].angle - res.bodies["sun"].angle * 24 / 90


def test_quasi_static_lumped_agrees_with_rigid():
    """Sun at 2 Hz (mesh 35 Hz, far below the first mode): the lumped model with the contact
    law's stiffness carries the rigid model's load per mesh and its transmission error."""
    slow = MERCURY.replace("speed_hz = 30.0", "speed_hz = 2.0")
    rigid = _run(slow, 0.1, 0.06)
    lumped = _run('model = "lumped"\n' + slow, 0.1, 0.06)
    for name, m in rigid.meshes.items():
        assert lumped.meshes[name].normal_force.mean() == pytest.approx(m.normal_force.mean(), rel=0.01)
    te_r, te_l = _twist(rigid), _twist(lumped)
    # the twist under load is about 2 x 2.4 um of mesh deflection over the 45 mm carrier radius,
    # 1e-4 rad; the means agree within 1 % of it, the ripples within 10 %
    assert abs(te_l.mean() - te_r.mean()) < 1e-6
    assert te_l.std() == pytest.approx(te_r.std(), rel=0.1)
    assert lumped.bodies["sun"].torque.mean() == pytest.approx(rigid.bodies["sun"].torque.mean(), rel=1e-3)


def test_lumped_run_has_the_results_layout(tmp_path):
    res = _run(LUMPED, 0.06, 0.02)
    validate(res)
    assert res.attrs["model"] == "lumped"
    assert 'model = "lumped"' in res.config_toml
    assert set(res.meshes) == {f"sun-planet{k}" for k in (1, 2, 3)} | {f"planet{k}-ring" for k in (1, 2, 3)}
    m = res.meshes["planet1-ring"]
    # the force on the ring acts along the line of action: |F_global| = F (to the anti-alias filter)
    assert np.allclose(np.hypot(*m.force_global.T), m.normal_force, rtol=2e-3)
    # kinematics: carrier at z_s / (z_s + z_r) of the sun's speed
    assert res.bodies["carrier"].angular_velocity.mean() == pytest.approx(2 * np.pi * 30 * 24 / 90, rel=1e-3)
    path = save(res, tmp_path / "results.h5")
    back = load(path)
    assert np.array_equal(back.meshes["sun-planet2"].normal_force, res.meshes["sun-planet2"].normal_force)


def test_iso_source_mean_and_tooth_pair_pattern():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "iso6336"\npositions = 24\n')
        lm = build_lumped(cfg)
    g = cfg.gears
    iso_sp = pair_stiffness(g["sun"].z, g["planet"].z, g["sun"].module, 0.02, alpha=g["sun"].pressure_angle).k_mesh
    assert lm.k[0].mean() == pytest.approx(iso_sp, rel=1e-12)
    # two levels (one and two tooth pairs), the double-contact share about eps - 1 = 0.59
    levels = np.unique(np.round(lm.k[0] / lm.k[0].min(), 6))
    assert list(levels) == [1.0, 2.0]
    assert np.mean(lm.k[0] > lm.k[0].min()) == pytest.approx(0.59, abs=0.1)


def test_a_contact_damping_ratio_the_lumped_stiffness_source_does_not_use_is_said():
    """With [lumped] mesh_stiffness other than contact the lumped meshes take [lumped]
    damping_ratio; a [contact] damping_ratio (the contact law's) was ignored without a word: the
    model says which one its meshes take, and takes it (c = 2 zeta sqrt(k m_eq))."""
    cfg = loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "iso6336"\npositions = 24\ndamping_ratio = 0.04\n')
    cfg.use_damping_ratio(0.05)
    with pytest.warns(UserWarning, match=r"\[contact\] damping_ratio = 0.05 damps the contact law; with \[lumped\] "
                                         r"mesh_stiffness = 'iso6336' the lumped meshes take \[lumped\] damping_ratio "
                                         r"= 0.04"):
        lm = build_lumped(cfg)
    lm0 = build_lumped(loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "iso6336"\npositions = 24\n'
                                    'damping_ratio = 0.04\n'))
    assert np.array_equal(lm.c, lm0.c) and np.allclose(lm.c[0] / np.sqrt(lm.k[0]), lm.c[0, 0] / np.sqrt(lm.k[0, 0]))


def test_backlash_and_contact_loss():
    """Load reversed at 0.1 s with 20 um backlash: the meshes run on the back flanks, lose
    contact while the gears cross the backlash, then run on the drive flanks (the flanks that
    the final load, where the model is linearised, presses)."""
    text = (LUMPED.replace("torque = 60.0", "torque = [[0.0, -20.0], [0.1, -20.0], [0.102, 20.0]]")
            + '\n[lumped]\nmesh_stiffness = "constant"\nbacklash = 2e-5\n'
            'constant_stiffness = {sun-planet = 2e8, planet-ring = 2.5e8}\n')
    res = _run(text, 0.0, 0.2)
    m = res.meshes["sun-planet1"]
    t = res.time
    side = m.pair_side[:, 0]
    assert np.all(side[(t > 0.06) & (t < 0.1)] == -1)
    assert np.all(side[t > 0.15] == 1)
    assert np.any(side[(t > 0.1) & (t < 0.15)] == 0)  # contact lost in between
    assert np.all(m.pair_force[side == 0, 0] == 0.0)  # (samples; normal_force is low-pass filtered)
    # the carrier turns back by the backlash: 2 b / (2 a cos(alpha)) per mesh pair in series
    twist = _twist(res)
    jump = twist[t > 0.15].mean() - twist[(t > 0.06) & (t < 0.1)].mean()
    assert abs(jump) > 2e-5 / 0.045  # at least one backlash over the carrier radius


def test_rotational_dofs_and_constant_stiffness_errors():
    with pytest.raises(ConfigError, match=r"lumped\.constant_stiffness\.planet-ring is missing"):
        loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "constant"\nconstant_stiffness = {sun-planet = 1e8}\n')
    with pytest.raises(ConfigError, match=r"lumped\.constant_stiffness\.sun-ring: no such pair"):
        loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "constant"\n'
                     'constant_stiffness = {sun-planet = 1e8, planet-ring = 1e8, sun-ring = 1e8}\n')
    with pytest.raises(ConfigError, match=r"lumped\.constant_stiffness\.sun-planet = -1.0: must be > 0"):
        loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "constant"\n'
                     'constant_stiffness = {sun-planet = -1.0, planet-ring = 1e8}\n')
    with pytest.raises(ConfigError, match=r"lumped\.mesh_stiffness = 'spline'"):
        loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "spline"\n')
    with pytest.raises(ConfigError, match=r"model = 'lumpy'"):
        loads_config('model = "lumpy"\n' + MERCURY)
    with pytest.raises(ConfigError, match=r"\[lumped\] given with model = 'rigid'"):
        loads_config(MERCURY + '\n[lumped]\ndofs = "rotational"\n')
    with pytest.raises(ConfigError, match="load.torque"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            build_lumped(loads_config(LUMPED.replace("torque = 60.0", "torque = 0.0")))


@pytest.mark.slow
def test_fe_source_follows_the_tooth_pair_pattern():
    """FE loaded-mesh stiffness (about 1 min with the meshes cached): two levels, the lower one
    (single tooth pair) where the real outlines have one pair in contact."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(LUMPED + '\n[lumped]\nmesh_stiffness = "fe"\npositions = 24\n')
        lm = build_lumped(cfg)
        ref = build_lumped(loads_config(LUMPED + '\n[lumped]\npositions = 24\n'))
    for m in range(lm.k.shape[0]):
        single = ref.k[m] < 0.8 * ref.k[m].max()  # one pair in contact (contact-law stiffness)
        low = lm.k[m] < 0.8 * lm.k[m].max()
        # where the real outlines carry one pair, so does the FE series (its single-pair zone is
        # wider: the outlines' tip corners touch lightly early, which the FE path leaves out)
        assert single.any() and np.all(low[single])
        assert low.mean() < 0.5
        assert 1e8 < lm.k[m].mean() < 1e9  # N/m: steel spur teeth, 20 mm face width


def test_spur_pair_lumped_statics_and_kinematics():
    """Spur preset as a lumped model: the mesh carries T / r_b (200 N m on the wheel) and the
    wheel turns at z_1 / z_2 of the pinion's speed."""
    text = 'model = "lumped"\n' + preset_path("spur_pair").read_text()
    res = _run(text, 0.1, 0.1)
    cfg = loads_config(text)
    F = 200.0 / cfg.gears["wheel"].rb
    assert res.meshes["pinion-wheel"].normal_force.mean() == pytest.approx(F, rel=2e-3)
    w_p = res.bodies["pinion"].angular_velocity.mean()
    assert res.bodies["wheel"].angular_velocity.mean() == pytest.approx(-w_p * 24 / 21, rel=1e-4)


@pytest.mark.parametrize("dofs", ["planar", "rotational"])
def test_elastic_bearings_carry_the_static_load(dofs):
    """Sun and planets on elastic bearings: every mesh carries the static share of the load
    (60 N m on the carrier: 16 N m on the sun, a third per planet over the sun's base radius),
    with the translations as coordinates or, with dofs = "rotational", the planets riding on
    their carrier pins."""
    text = (LUMPED.replace('planets = "revolute"  #', 'planets = {stiffness = 1e8, damping = 500.0}  #')
            .replace('sun = "revolute"      #', 'sun = {stiffness = 1e8, damping = 500.0}  #')
            + f'\n[lumped]\ndofs = "{dofs}"\n')
    res = _run(text, 0.1, 0.1)
    F = 60.0 / (1 + 66 / 24) / 3 / loads_config(MERCURY).gears["sun"].rb
    for name, m in res.meshes.items():
        assert m.normal_force.mean() == pytest.approx(F, rel=5e-3), name
    assert res.attrs["rejected_steps"] < 0.01 * res.attrs["solver_steps"]  # contact states settle


def test_a_diverging_lumped_run_names_the_time_and_the_mesh(monkeypatch):
    """A state that turns non-finite stops the run with a DivergenceError giving the first
    non-finite step's time and the mesh carrying the largest force before it (never NaN output).
    The blow-up is injected after the first 400 steps of a chunk."""
    import flexgear.dynamics.lumped.time_loop as ls
    from flexgear.errors import DivergenceError

    real = ls.integrate_lumped

    def blow_up(q, v, a, start, k, *args):
        real(q, v, a, start, k, *args)
        if k > 400:
            records = args[-2]  # a LumpedRecords window
            rec_q, rec_F = records.q, records.force
            rec_q[400:] = np.nan
            rec_F[399] = 0.0
            rec_F[399, 1] = 1e9  # the second mesh carries the largest force the step before
            q[:] = np.nan

    blow_up.signatures = ["compiled"]  # skip the separate compile call
    monkeypatch.setattr(ls, "integrate_lumped", blow_up)
    with pytest.raises(DivergenceError) as err:
        _run(LUMPED, 0.05, 0.05)
    msg = str(err.value)
    cfg = loads_config(LUMPED)
    h, _ = time_grid(cfg.simulation, cfg.mesh_frequency())  # the step the run used
    assert f"t = {401 * h:.6f} s" in msg
    from flexgear.dynamics.model.assembly import build_model

    assert f"mesh {build_model(loads_config(LUMPED)).meshes[1].name!r}" in msg
    assert "1e+09 N" in msg
