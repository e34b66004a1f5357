"""The condensed modes' coordinates in the results: what the solver used, and what they add.

A flexible gear's condensed modes (between ``[flexible] dynamic_cutoff`` and ``cutoff``) are
integrated inside the contact solve (:mod:`flexgear.dynamics.flexible.condensed`); their coordinates
eta_i are recorded at the output instants (``/bodies/<body>/condensed_coordinates``) and the
deformed field (:mod:`flexgear.results.deformed`) puts ``Phi_c eta_c`` in place of their
quasi-static response. Checked on a spur pair made to excite its modes: the modulus scaled by
0.1 (first clamped modes 9.9 and 13.7 kHz) and the pinion at 150 Hz (mesh frequency 3.6 kHz,
its harmonics and the tooth entries reach the modes), 20 N m. There the modes' own inertia and
the frames' inertia load make the flank deflection differ from the static one by up to 2.8
times itself, so a field built from anything but the solver's own coordinates misses ``pair_deflection``.
"""
import warnings

import numpy as np
import pytest

from flexgear.app.run import run
from flexgear.config import load_config
from flexgear.dynamics.integrator.simulation import largest_modal_coordinate
from flexgear.results.deformed import DeformedGears


def excited_spur(condensation="integrated"):
    cfg = load_config("spur_pair_flexible")
    cfg.flexible.update(level=1, formulation="plane_stress", modulus_scale=0.1, cutoff=60e3,
                        condensation=condensation)
    cfg.drive["speed_hz"] = 150.0
    cfg.load.update(torque=20.0, ramp=0.004)
    cfg.simulation.update(run_in=0.006, duration=0.002, output_rate=10000.0)
    cfg.contact["outline_spacing"] = 2e-5  # module/100: the contact tables build 4x faster
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the cutoff below static_frequency(h): deliberate, fewer modes
        return run(cfg)


@pytest.fixture(scope="module")
def excited():
    res = excited_spur()
    return res, DeformedGears(res, stresses=False)


def test_a_flexible_result_says_it_is_flexible(excited, tmp_path):
    """The root attribute ``model`` names the model that ran: the multi-body model with flexible
    gears is ``flexible`` (the configuration's ``model`` key stays "rigid", the default), in
    memory and in the file."""
    from flexgear.results.store import load, save

    res = excited[0]
    assert res.attrs["model"] == "flexible"
    assert load(save(res, tmp_path / "r.h5")).attrs["model"] == "flexible"


def deflection_errors(dg):
    """Relative error of the field's flank deflection (both gears, :meth:`DeformedGears.frame`)
    against the recorded pair_deflection at every loaded tooth pair of every sample."""
    res = dg.result
    rec = res.meshes["pinion-wheel"]
    errors = []
    for i in range(len(res.time)):
        frame = dg.frame(i)
        assert frame.unmatched == []
        per = {}
        for g in frame.gears:
            for ld in g.loads:
                per.setdefault(ld.slot, []).append(ld)
        for s, lds in per.items():
            if lds[0].force > 0.05 * rec.pair_force[i].sum():
                assert len(lds) == 2
                errors.append(sum(ld.deflection for ld in lds) / rec.pair_deflection[i, s] - 1.0)
    return np.array(errors)


def test_recorded_condensed_coordinates_are_those_the_solver_used(excited):
    """With the recorded eta_c in the field, the flank deflection at every loaded pair equals
    the solver's ``pair_deflection`` within 1 % (the flank tables' linear interpolation in the
    radius, as for the static field: tests/test_deformed.py); with the condensed modes at their
    static response to the contact loads instead it misses by far more (measured: 0.08 % against
    up to 2.8 times the deflection: the modes' inertia and the frames' inertia load), and with
    the coordinates of the next sample (a record shifted by one row: 1.3 times) too."""
    res, dg = excited
    for name in ("pinion", "wheel"):
        b = res.bodies[name]
        red = next(r for _, n, _, _, r in dg.bodies if n == name)
        nq = red.body.n_modes  # dynamic_cutoff 8 kHz is below the first mode: every mode condensed
        assert b.condensed_coordinates.shape == (len(res.time), nq)
        assert np.allclose(b.attrs["condensed_frequencies"], red.body.frequencies, rtol=1e-12)
        assert np.all(np.isfinite(b.condensed_coordinates)) and np.abs(b.condensed_coordinates).max() > 0
    e = deflection_errors(dg)
    static = deflection_errors(DeformedGears(res, stresses=False, condensed={}))
    shifted = deflection_errors(DeformedGears(res, stresses=False, condensed={
        n: np.roll(c, -1, axis=0) for n, c in dg.condensed.items()}))
    print(f"field vs pair_deflection over {e.size} pairs: recorded eta_c max |error| {np.abs(e).max():.2e} "
          f"(mean {e.mean():+.1e}); static condensed modes {np.abs(static).max():.3f}; next sample's eta_c "
          f"{np.abs(shifted).max():.3f}")
    assert e.size >= 20
    assert np.abs(e).max() < 0.01
    assert abs(e.mean()) < 0.003
    assert np.abs(static).max() > 0.1  # the check is sharp: the modes' dynamics matter here
    assert np.abs(shifted).max() > 0.1


def test_static_condensation_records_the_static_response():
    """With ``condensation = "static"`` the recorded eta_c are the modes' static response to
    the contact forces and the frames' inertia load, the response the solver's flank
    deflection stood for: the field with them matches ``pair_deflection`` within 1 % too
    (measured 0.09 %), the static field of the contact loads alone does not."""
    res = excited_spur("static")
    dg = DeformedGears(res, stresses=False)
    e = deflection_errors(dg)
    bare = deflection_errors(DeformedGears(res, stresses=False, condensed={}))  # contact loads only
    print(f"static condensation: field vs pair_deflection max |error| {np.abs(e).max():.2e} over {e.size} pairs; "
          f"without the frames' inertia load {np.abs(bare).max():.3f}")
    assert e.size >= 20
    assert np.abs(e).max() < 0.01
    assert np.abs(bare).max() > 0.1  # measured 2.2 times the deflection: the frames' inertia load


def test_divergence_text_names_the_largest_condensed_mode(excited):
    """``largest_modal_coordinate`` with the condensed state names the body and mode (its number
    in the body's reduction) whose eta_i moves a flank most, with the mode's frequency."""
    res, dg = excited
    model = dg.model
    nq = [fb.shape.shape[3] for fb in model.flex]
    eta = np.zeros(sum(nq))
    wheel = next(k for k, fb in enumerate(model.flex) if model.bodies[fb.body].name == "wheel")
    fb = model.flex[wheel]
    j = 4
    eta[sum(nq[:wheel]) + j] = 1e-6
    text = largest_modal_coordinate(model, np.zeros(model.rigid_coordinates()), eta)
    f = fb.condensed_omega[j] / (2 * np.pi)
    A = np.abs(fb.shape[..., j]).max() * fb.condensed_omega[j]
    assert text == (f"; largest condensed mode: body 'wheel' mode {j + 1} ({f:.4g} Hz), eta = 1e-06 sqrt(kg) m, "
                    f"flank displacement up to {A * 1e-6 * 1e6:.4g} um")
    assert largest_modal_coordinate(model, np.zeros(model.rigid_coordinates())) == ""
