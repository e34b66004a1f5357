"""Step aliases (issue 25, section 5): lines at |n f_m - j/h| next to the mesh lines, and the
synchronous step that removes them.

The integrator evaluates the contact forces only at its steps and the solver records them
there, before any filter. Each tooth pair enters contact with a force growing as delta^e from
zero within a few tens of microseconds, so the mesh force has content at mesh harmonics far
above the output band (MERCURY 1-A: 0.02-0.05 N per harmonic around 40 kHz). A harmonic n f_m
next to a multiple j/h of the step rate is seen at the step as a line |n f_m - j/h| from a mesh
line: in MERCURY 1-A at 25 us, 76 f_m - 40 kHz = 128 Hz, lines of 0.1-0.2 N beside the mesh
lines of the planet-ring force (0.3 % of them: the size of a fault's sidebands). With the step
rate a whole multiple of the mesh frequency (``simulation.synchronous``), every such component
folds onto a mesh harmonic and nothing stands between the mesh lines.

Measure: the planet1-ring normal force and vertical force of the output, Blackman-Harris window
(leakage below -92 dB); a line's level is taken relative to its neighbouring mesh line (the
largest of k f_m and its carrier sidebands k f_m +- f_c, which the turning carrier and the
planets' weight put there).
"""
import warnings

import pytest
from scipy.signal import get_window

from conftest import load_script
from flexgear.app.run import run
from flexgear.config import load_config, time_grid
from flexgear.results.signals import amplitude_spectrum

STUDY = load_script("studies/step_aliases.py")  # fold(), off_set_lines(): the study's measure

F_IN, Z_S, Z_R = 30.0, 24, 66
F_C = F_IN * Z_S / (Z_S + Z_R)  # 8 Hz carrier
F_M = Z_R * F_C  # 528 Hz mesh
FLOOR = 1e-4  # the bar: 0.01 % of the neighbouring mesh line


def mercury(duration, run_in=0.2, **sim):
    cfg = load_config("mercury_1a")
    cfg.simulation.update(duration=duration, run_in=run_in, **sim)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(cfg)


def spectrum(res, component):
    m = res.meshes["planet1-ring"]
    x = m.normal_force if component == "normal" else m.force_global[:, 1]
    return amplitude_spectrum(x, res.fs, window=get_window("blackmanharris", len(x)))


def off_set_lines(res, component):
    """:func:`off_set_lines` of the study on the planet1-ring force of ``res``."""
    f, A = spectrum(res, component)
    return STUDY.off_set_lines(f, A, F_M, F_C)


@pytest.fixture(scope="module")
def short_runs():
    """0.25 s (two carrier turns) after the 0.2 s run-in: the plain 25 us and 20 us grids at
    10 kHz, and the synchronous grid from the 25 us step."""
    return {"25us": mercury(0.25, synchronous=False),
            "20us": mercury(0.25, synchronous=False, step=2e-5),
            "sync": mercury(0.25, synchronous=True)}


# ----------------------------------------------------------------------------- the grid rule
@pytest.mark.parametrize("f_mesh, step, rate", [(528.0, 2.5e-5, 1e4), (240.0, 2.5e-5, 1e4), (528.0, 6.25e-6, 1e4),
                                                (545.6, 2.5e-5, 5e3), (528.0, 1e-4, 1e4), (1234.5, 3e-5, 2.6e4),
                                                (528.0, 2.5e-5, 100.0)])
def test_synchronous_grid_is_a_whole_number_of_steps_and_of_samples_per_mesh_period(f_mesh, step, rate):
    """Whole steps and whole output samples per mesh period (below f_m: whole mesh periods per
    sample), the output rate the least of them at or above the one asked, the fewest steps per
    sample that keep h <= step; the rule gives its own grid back."""
    sim = {"output_rate": rate, "step": step, "synchronous": True}
    h, every = time_grid(sim, f_mesh)
    n = 1.0 / (f_mesh * h)
    assert n == pytest.approx(round(n), abs=1e-9) and h <= step * (1 + 1e-12)  # whole steps per mesh period
    out = 1.0 / (every * h)
    if rate >= f_mesh:
        m = out / f_mesh  # output samples per mesh period
        assert m == pytest.approx(round(m), abs=1e-9) and rate <= out * (1 + 1e-12) < rate + f_mesh
        assert every == 1 or 1.0 / (f_mesh * round(m) * (every - 1)) > step  # the fewest steps per sample
    else:
        p = f_mesh / out  # mesh periods per output sample
        assert p == pytest.approx(round(p), abs=1e-9) and rate <= out * (1 + 1e-12)
        assert f_mesh / (round(p) + 1) < rate  # the most mesh periods per sample
        assert 1.0 / (f_mesh * (round(n) - 1)) > step
    assert time_grid(dict(sim, step=h, output_rate=out), f_mesh) == (h, every)  # the grid reproduces itself
    assert time_grid(sim) == time_grid(dict(sim, synchronous=False))  # no mesh frequency: the plain rule


def test_the_synchronous_grid_of_mercury_and_what_the_result_records(short_runs):
    r = short_runs["sync"]
    assert r.attrs["step"] == pytest.approx(1.0 / (76 * F_M), rel=1e-12)  # 76 steps per mesh period
    assert r.attrs["output_rate"] == pytest.approx(19 * F_M, rel=1e-12)  # 4 steps per output sample
    assert "76 steps per mesh period" in r.attrs["notes"]
    a = short_runs["25us"]
    assert a.attrs["step"] == 2.5e-5 and a.attrs["output_rate"] == 1e4


@pytest.mark.parametrize("preset, steps", [("mercury_1a", 76), ("spur_pair", 168)])
def test_the_rigid_presets_run_on_the_synchronous_grid(preset, steps):
    """The presets' spectra are what users read first (README's first command)."""
    cfg = load_config(preset)
    assert cfg.simulation["synchronous"] is True
    h, _ = time_grid(cfg.simulation, cfg.mesh_frequency())
    assert h * cfg.mesh_frequency() * steps == pytest.approx(1.0, rel=1e-12)


def test_a_speed_table_keeps_the_plain_grid_with_a_warning():
    cfg = load_config("mercury_1a")
    cfg.drive["speed_hz"] = [[0.0, 20.0], [0.01, 30.0]]
    cfg.simulation.update(duration=0.002, run_in=0.0, synchronous=True)
    with pytest.warns(UserWarning, match=r"simulation\.synchronous = true not applied: drive\.speed_hz is a table"):
        r = run(cfg)
    assert r.attrs["step"] == 2.5e-5 and r.attrs["output_rate"] == 1e4


# ----------------------------------------------------------------------------- the lines
@pytest.mark.parametrize("component", ["normal", "vertical"])
def test_plain_grid_lines_sit_where_the_step_folds_the_mesh_harmonics(short_runs, component):
    """At 25 us the largest component between the mesh lines up to 4 kHz lies 128 Hz from one
    (76 f_m - 40 kHz) and exceeds 0.1 % of it (measured up to 1 %); at 20 us 160 Hz (95 f_m -
    50 kHz). A kinematic line or a periodicity of the contact tables would not move with the
    step."""
    for key, h in (("25us", 2.5e-5), ("20us", 2e-5)):
        r = STUDY.fold(1.0 / h, F_M)
        assert r == pytest.approx(128.0 if key == "25us" else 160.0)
        lines = off_set_lines(short_runs[key], component)
        k, ref, fl, a = max(lines, key=lambda x: x[3])
        assert abs(abs(fl - k * F_M) - r) <= 8.0 + F_C, (key, k, fl)  # two bins, or a carrier sideband of it
        assert max(x[3] / x[1] for x in lines) > 1e-3, key


@pytest.mark.parametrize("component", ["normal", "vertical"])
def test_synchronous_grid_leaves_nothing_between_the_mesh_lines(short_runs, component):
    """The synchronous grid: below 0.01 % of the neighbouring mesh line everywhere
    between the mesh lines and their carrier sidebands up to 4 kHz (measured: at the window's
    leakage floor)."""
    worst = max(a / ref for _, ref, _, a in off_set_lines(short_runs["sync"], component))
    assert worst < FLOOR, worst


# ----------------------------------------------------------------------------- slow: 1 s
@pytest.mark.slow
@pytest.mark.parametrize("preset, mesh, f_mesh", [("mercury_1a", "planet1-ring", F_M), ("spur_pair", "pinion-wheel", 240.0)])
def test_preset_spectra_have_no_step_aliases(preset, mesh, f_mesh):
    """The presets (1 s after the run-in, 1 Hz resolution), synchronous: every component off the
    set k f_m +- {0, 1, 2} f_c (f_c = 0 for the spur pair) up to 4 kHz is below 0.01 % of its
    neighbouring mesh line; with ``synchronous = false`` the step aliases exceed it (MERCURY 1-A:
    0.1-0.22 N at k f_m +- 128 Hz, the issue's lines; spur pair: 25-90 mN at k f_m +- 80 Hz)."""
    def worst(sync):
        cfg = load_config(preset)
        cfg.simulation["synchronous"] = sync
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = run(cfg)
        fc = res.attrs["carrier_frequency"]
        out = 0.0
        for x in (res.meshes[mesh].normal_force, res.meshes[mesh].force_global[:, 1]):
            f, A = amplitude_spectrum(x, res.fs, window=get_window("blackmanharris", len(x)))
            out = max(out, max(a / ref for _, ref, _, a in STUDY.off_set_lines(f, A, f_mesh, fc, guard=2.6)))
        return out

    assert worst(True) < FLOOR
    assert worst(False) > 3 * FLOOR


def test_synchronous_grid_of_a_set_driven_backwards():
    """A negative drive speed gives a negative mesh frequency: the synchronous grid is that of
    its magnitude (a negative step integrated the run backwards in time)."""
    sim = load_config("mercury_1a").simulation
    assert time_grid(sim, -528.0) == time_grid(sim, 528.0)
    assert time_grid(sim, -528.0)[0] > 0


def test_the_lumped_spur_pair_leaves_nothing_between_its_mesh_lines():
    """The lumped spur pair's record: its force's harmonics above the output's Nyquist frequency,
    what the anti-alias filter leaves of them, fold onto mesh lines as the output holds a whole
    number of samples per mesh period (42; at 41.75 they made lines of 0.2 % of a mesh line at
    (k + 3/4) f_m): between the mesh lines up to 4 kHz below 0.01 % of the neighbouring one."""
    cfg = load_config("spur_pair:lumped").use_damping_ratio(0.05)
    cfg.simulation.update(duration=0.5)
    res = run(cfg)
    fm = res.attrs["mesh_frequency"]
    assert res.attrs["output_rate"] / fm == pytest.approx(42.0, rel=1e-12)
    f, A = amplitude_spectrum(res.meshes["pinion-wheel"].normal_force, res.attrs["output_rate"], window="hann")
    df = f[1] - f[0]
    worst = 0.0
    for k in range(1, int(4000.0 / fm)):
        ref = A[abs(f - k * fm) <= 2 * df].max()
        between = (f > k * fm + 3 * df) & (f < (k + 1) * fm - 3 * df)
        worst = max(worst, A[between].max() / ref)
    assert worst < FLOOR, worst
