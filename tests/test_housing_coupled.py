"""The housing coupled into the multi-body model (issue 23, item 1; ``[housing] coupled = true``).

The spur pair preset with its default housing and two sensors, its shafts on elastic bearings
(5e8 N/m, 2e3 N s/m) seated in the housing, short runs (0.1 s kept after a 0.1 s run-in; the
load ramps up over 0.05 s, the housing's lowest mode on its feet, near 1 kHz at 2 % damping,
decays in about 8 ms).
"""
from __future__ import annotations

import numpy as np
import pytest

import flexgear.app.run as run_module
from flexgear.app.run import run
from flexgear.config.loader import loads_config, preset_path, time_grid
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.housing import couple_housing, foot_reactions, ground_moment
from flexgear.errors import ConfigError
from flexgear.reduction.housing import reduce_housing

RIGID = 'pinion = "revolute"\nwheel = "revolute"'
BEARINGS = 'pinion = {stiffness = 5.0e8, damping = 2.0e3}\nwheel = {stiffness = 5.0e8, damping = 2.0e3}'
CAST_IRON_E = 1.1e11


def config(coupled=True, supports=BEARINGS, stiffen=1.0, quantity="acceleration", duration=0.1, model=None):
    """The spur pair with its housing; ``stiffen`` multiplies the housing's E and foot stiffness
    (and its cutoff by sqrt(stiffen): the fixed-interface modes rise as sqrt(E))."""
    s = preset_path("spur_pair_sensors").read_text().replace(RIGID, supports)
    s = s.replace("damping_ratio = 0.02  # modal, of the housing on its feet",
                  f"damping_ratio = 0.02\ncoupled = {str(coupled).lower()}\nE = {CAST_IRON_E * stiffen}\n"
                  f"foot_stiffness = {1e8 * stiffen}\ncutoff = {50e3 * np.sqrt(stiffen)}")
    s = s.replace("duration = 1.0", f"duration = {duration}").replace("run_in = 0.2", "run_in = 0.1")
    s = s.replace('quantity = "acceleration"', f'quantity = "{quantity}"')
    if model is not None:
        s = f'model = "{model}"\n' + s
    return loads_config(s)


def test_feet_balance_the_shaft_torques():
    """Steady state: the feet's ground reactions balance the input and output torques (issue 23,
    0.1 %). The gear set and housing are free but for the shafts' torques and the feet, so over
    whole mesh periods of a periodic state (momenta repeat) the ground's moment is -(T_in +
    T_out) and its force zero. A reaction not passed to the housing, a wrong seat, sign or force
    share breaks the balance."""
    cfg = config()
    model = build_model(cfg)
    red = reduce_housing(cfg.housing)
    couple_housing(model, red)
    fm = cfg.mesh_frequency()
    per = 160  # steps per mesh period
    h = 1.0 / (fm * per)
    integ = simulate(model, 0.15, h, 4)
    nh = model.housing.n
    last = slice(integ.nsteps - 10 * per, integ.nsteps)  # the last 10 mesh periods
    q_h = integ.modal[last, -nh:]
    wheel = [b.name for b in model.bodies].index("wheel")
    t_in = integ.body[last, 0, 6].mean()  # the pinion's drive torque
    t_out = float(model.bodies[wheel].torque(0.15))  # the load, ramped up by 0.05 s
    assert abs(t_in) > 100.0 and abs(t_out) > 100.0
    m_feet = ground_moment(red, q_h).mean()
    assert abs(m_feet + t_in + t_out) < 1e-3 * abs(t_in + t_out), (m_feet, t_in, t_out)
    F = foot_reactions(red, q_h).sum(axis=1).mean(axis=0)
    mesh = integ.mesh[last, 0, 0].mean()  # the normal mesh force each seat carries
    assert np.hypot(*F) < 1e-3 * mesh, (F, mesh)


@pytest.fixture(scope="module")
def runs():
    """Uncoupled (one-way path), coupled, and coupled with a 100 times stiffer housing and feet;
    sensors in displacement (no differentiation error in the comparison)."""
    return {name: run(config(**kw)) for name, kw in (
        ("one_way", dict(coupled=False, quantity="displacement")),
        ("coupled", dict(quantity="displacement")),
        ("stiff", dict(stiffen=100.0, quantity="displacement")))}


def _departure(a, b):
    return np.std(a - b) / np.std(a)


def test_stiff_housing_approaches_uncoupled(runs):
    """The uncoupled model is the limit of a rigid housing on rigid feet: scaling the housing's
    compliance by 1/100 shrinks the coupled mesh force's departure from the uncoupled one by far
    more than 10 (first order in the compliance: 100), while the nominal housing departs
    visibly (else the coupling did nothing)."""
    f = {k: r.meshes["pinion-wheel"].normal_force for k, r in runs.items()}
    nominal = _departure(f["one_way"], f["coupled"])
    stiff = _departure(f["one_way"], f["stiff"])
    assert nominal > 1e-2, nominal
    assert stiff < nominal / 10.0, (stiff, nominal)


def _line(x, rate, f):
    t = np.arange(x.size) / rate
    return 2.0 * abs(np.mean((x - x.mean()) * np.exp(-2j * np.pi * f * t)))


def test_coupled_sensor_against_one_way_path(runs):
    """Where the feedback is negligible the two paths agree.

    * The mean displacement is the housing's static response to the mean bearing loads, which
      equilibrium fixes whatever the housing's compliance: both paths give it to 1e-3 of the
      larger sensor's (the static response's scale; what is left is the mean of the dynamic
      part over 24 mesh periods).
    * The mesh-frequency line (240 Hz) lies well below the housing's lowest mode on its feet
      f_1: the housing moves quasi-statically there, its dynamic part, (f_m / f_1)^2 of the
      static, bounds how much its motion changes the bearing forces, and so the line's
      difference between the paths.

    A wrong seat, force share or sensor row moves either by order 1."""
    one, cpl = runs["one_way"], runs["coupled"]
    rate = 1.0 / (one.time[1] - one.time[0])
    fm = 240.0
    means = {n: one.sensors[n].signals["housing_path"].mean() for n in ("top", "side")}
    scale = max(abs(m) for m in means.values())
    for name in ("top", "side"):
        a = one.sensors[name].signals["housing_path"]
        b = cpl.sensors[name].signals["housing_coupled"]
        assert "housing_path" not in cpl.sensors[name].signals
        assert abs(b.mean() - a.mean()) < 1e-3 * scale, (name, a.mean(), b.mean())
        f1 = one.sensors[name].signal_attrs["housing_path"]["lowest_mode_hz"]
        la, lb = _line(a, rate, fm), _line(b, rate, fm)
        assert la > 0 and abs(lb - la) < (fm / f1) ** 2 * la, (name, la, lb, f1)


@pytest.mark.parametrize("case, match", [
    (dict(supports=RIGID), "supports.pinion"),
    (dict(model="lumped"), "housing.coupled = true with model"),
])
def test_bad_input(case, match):
    """A shaft on a rigid joint cannot seat in a coupled housing; the lumped model has no housing
    body: each a ConfigError naming the key, before anything is built."""
    with pytest.raises(ConfigError, match=match):
        run(config(**case))


def test_planetary_on_rigid_joints_refused():
    """mercury_1a_sensors seats its sun on a revolute joint: coupling its housing names the
    support (the coupled planetary set: tests/test_housing_coupled_planetary.py)."""
    s = preset_path("mercury_1a_sensors").read_text()
    s = s.replace("[housing]", "[housing]\ncoupled = true", 1)
    with pytest.raises(ConfigError, match="supports.sun"):
        run(loads_config(s))


def test_models_without_a_coupled_housing_pack_an_empty_table_of_the_same_type():
    """Every other model passes an empty housing table to the kernels, of the coupled table's
    numba type, so both run one compiled solver (a type of its own would compile the whole
    solver again; the run stays bit-identical: tests/test_regression.py); a coupled one a table
    of its coordinates after every other."""
    import numba

    cfg = config()
    plain = build_model(config(coupled=False))
    coupled = build_model(cfg)
    couple_housing(coupled, reduce_housing(cfg.housing))
    kp, kc = plain.pack(), coupled.pack()
    assert kp.housing.stiffness.shape == (0, 0) and kp.housing.link_body.shape == (0,)
    assert numba.typeof(kp) == numba.typeof(kc)
    n = len(coupled.initial_state()[0])
    assert kc.housing.first == n - coupled.housing.n == len(plain.initial_state()[0])
    assert coupled.coordinate_names()[kc.housing.first].startswith("housing.")


def test_ring_anchor_rows_follow_the_bolts():
    """MERCURY 1-A's housing: bolts moved as one rigid body (u_x, u_y, theta) give the ring's
    anchor that motion, and the rows' transpose shares a ring load over the bolts exactly as the
    one-way path's inputs do (the same statically equivalent share)."""
    from flexgear.dynamics.model.housing import bolt_anchor_rows
    from flexgear.reduction.paths import housing_inputs

    cfg = loads_config(preset_path("mercury_1a_sensors").read_text())
    red = reduce_housing(cfg.housing)
    G = bolt_anchor_rows(red)
    E = red.ring_coupling()
    np.testing.assert_allclose(G @ E, np.eye(3), atol=1e-12)
    share = housing_inputs(red)
    np.testing.assert_allclose(G.T, np.column_stack([share[c] for c in ("ring.x", "ring.y", "ring.moment")]),
                               atol=1e-12)


def test_record_estimate_counts_the_housing_coordinates():
    """The coupled housing's coordinates are recorded with the modal ones at every step:
    :func:`~flexgear.app.run.record_bytes` with the coupled model equals the bytes of every
    record the solver returns (an estimate that left them out would pass a run that does not
    fit in memory)."""
    cfg = config()
    model = build_model(cfg)
    couple_housing(model, reduce_housing(cfg.housing))
    h, every = time_grid(cfg.simulation)
    n_out = 8
    r = simulate(model, n_out * every * h, h, every)
    assert r.records.modal.shape[1] == model.housing.n > 0
    assert run_module.record_bytes(cfg, n_out, every, model) == sum(a.nbytes for a in r.records)
