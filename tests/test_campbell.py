"""Campbell diagram crossings, and resonances of a stepped speed sweep at the linearised modes."""
import warnings

import numpy as np
import pytest

from flexgear.app.run import time_grid
from flexgear.config import loads_config, preset_path
from flexgear.dynamics.modal.campbell import crossings, line_label
from flexgear.dynamics.lumped.planetary import lin_parker_example, planetary_system
from flexgear.dynamics.lumped.model import at_speed, build_lumped
from flexgear.dynamics.lumped.time_loop import simulate_lumped
from flexgear.dynamics.modal.linearise import linearise
from flexgear.dynamics.modal.system import modes
from flexgear.errors import ConfigError
from flexgear.results.campbell_plot import fig_campbell
from flexgear.results.signals import amplitude_spectrum, line_amplitude
from flexgear.style import save_figure

MERCURY = preset_path("mercury_1a").read_text()


def test_crossings_meet_the_natural_frequencies():
    fn = [0.0, 1000.0, 2500.0]
    cr = crossings(fn, ["rotational", "planet", "rotational"], mesh_ratio=17.6, carrier_ratio=0.2667,
                   speed_range=(1.0, 200.0), harmonics=4, sidebands=1)
    assert [c.input_speed for c in cr] == sorted(c.input_speed for c in cr)
    for c in cr:
        assert c.input_speed * (c.harmonic * 17.6 + c.sideband * 0.2667) == pytest.approx(c.frequency, rel=1e-12)
        assert c.frequency > 0 and c.label == line_label(c.harmonic, c.sideband)
    assert len(cr) == 2 * 4 * 3  # every line meets both elastic modes inside the range
    assert line_label(4, -1) == "4f_m-f_a" and line_label(1, 0) == "f_m"
    with pytest.raises(ConfigError, match="speed range"):
        crossings(fn, ["-"] * 3, 17.6, 0.27, (10.0, 5.0))


def test_campbell_figure(tmp_path):
    res = modes(planetary_system(lin_parker_example(4)))
    fig, cr = fig_campbell(res, 20.0, 0.3, (5.0, 150.0))
    assert cr and all(5.0 <= c.input_speed <= 150.0 for c in cr)
    assert save_figure(fig, tmp_path / "campbell.png").stat().st_size > 10_000


def test_lumped_sweep_resonance_at_the_first_mode():
    """Stepped sweep of the lumped model: the 4th mesh harmonic of the sun-planet force peaks where
    4 f_m meets the first linearised natural frequency (within 3 %)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config('model = "lumped"\n' + MERCURY)
        lm = build_lumped(cfg)
        f1 = modes(linearise(lm.model)).frequencies[0]
    r_m = lm.model.attrs["mesh_frequency"] / lm.model.attrs["input_frequency"]
    s0 = f1 / (4 * r_m)
    h, oe = time_grid(cfg.simulation)
    speeds = s0 * np.linspace(0.9, 1.1, 21)
    amp = []
    for s in speeds:
        integ = simulate_lumped(at_speed(lm, s), 0.3, h, oe)
        F = integ.mesh[int(0.15 / h):, 0, 0]
        f, A = amplitude_spectrum(F, 1 / h)
        amp.append(line_amplitude(f, A, 4 * r_m * s, tol_hz=10.0))
    i = int(np.argmax(amp))
    assert 0 < i < len(speeds) - 1  # a peak inside the range
    assert 4 * r_m * speeds[i] == pytest.approx(f1, rel=0.03)
    assert amp[i] > 1.5 * min(amp[0], amp[-1])


@pytest.mark.slow
def test_rigid_sweep_resonance_at_the_linearised_mode():
    """Stepped sweep of the rigid model around 4 f_m = f_1: the 4th harmonic of the sun-planet
    force peaks within 3 % of the linearised first natural frequency (about 40 s)."""
    import flexgear

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(MERCURY)
        from flexgear.dynamics.model.assembly import build_model

        model = build_model(cfg)
        f1 = modes(linearise(model)).frequencies[0]
    r_m = model.attrs["mesh_frequency"] / model.attrs["input_frequency"]
    speeds = f1 / (4 * r_m) * np.linspace(0.94, 1.06, 7)
    amp = []
    for s in speeds:
        c = loads_config(MERCURY)
        c.drive["speed_hz"] = float(s)
        c.simulation.update(run_in=0.15, duration=0.25, output_rate=20000.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = flexgear.run(c)
        f, A = amplitude_spectrum(res.meshes["sun-planet1"].normal_force, res.fs)
        amp.append(line_amplitude(f, A, 4 * r_m * s, tol_hz=10.0))
    i = int(np.argmax(amp))
    assert 0 < i < len(speeds) - 1
    d = (amp[i - 1] - amp[i + 1]) / (2 * (amp[i - 1] - 2 * amp[i] + amp[i + 1]))
    peak = speeds[i] + d * (speeds[1] - speeds[0])
    assert 4 * r_m * peak == pytest.approx(f1, rel=0.03)
