"""Campbell diagram crossings, and resonances of a stepped speed sweep at the linearised modes."""
import math
import warnings

import numpy as np
import pytest

from flexgear.app.run import time_grid
from flexgear.config import loads_config, preset_path
from flexgear.dynamics.modal.campbell import crossings, excites, line_label, modal_crossings
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
    """f_in k r_m = f_n at every crossing of the lines k f_m; the carrier sidebands k f_m +- f_a
    (what a fixed sensor hears of the carrier-frame excitation k f_m) are no crossings of their
    own: 2 elastic modes x 4 harmonics, all inside the range (before: 24, with the sidebands)."""
    fn = [0.0, 1000.0, 2500.0]
    cr = crossings(fn, ["-", "-", "-"], mesh_ratio=17.6, speed_range=(1.0, 200.0), harmonics=4)
    assert [c.input_speed for c in cr] == sorted(c.input_speed for c in cr)
    for c in cr:
        assert c.input_speed * c.harmonic * 17.6 == pytest.approx(c.frequency, rel=1e-12)
        assert c.frequency > 0 and c.label == line_label(c.harmonic) and c.excited
    assert len(cr) == 2 * 4
    assert line_label(4) == "4f_m" and line_label(1) == "f_m"
    with pytest.raises(ConfigError, match="speed range"):
        crossings(fn, ["-"] * 3, 17.6, (10.0, 5.0))
    with pytest.raises(ConfigError, match="harmonics = 0"):
        crossings(fn, ["-"] * 3, 17.6, (1.0, 5.0), harmonics=0)


def parker_types(k: int, z_s: int, N: int) -> set:
    """Mode types the k-th mesh harmonic excites, as Parker (2000) states the rule for equally
    spaced planets: rotational if k z_s / N is an integer, translational if (k z_s +- 1) / N is,
    planet modes otherwise."""
    if (k * z_s) % N == 0:
        return {"rotational"}
    if (k * z_s + 1) % N == 0 or (k * z_s - 1) % N == 0:
        return {"translational"}
    return {"planet"}


def test_mercury_in_phase_planets_excite_rotational_modes_only():
    """MERCURY 1-A: z_s = 24, N = 3, z_s / N = 8 (planets in phase): every mesh harmonic excites
    the rotational modes only; the crossings with the planet modes (7.10 kHz, the central
    members of the rigid model only turn: j = +-1 modes are planet modes) are suppressed."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config('model = "lumped"\n' + MERCURY)
        lm = build_lumped(cfg)
        res = modes(linearise(lm.model))
    z_s, N = cfg.gears["sun"].z, cfg.planetary["planets"]
    assert (z_s, N) == (24, 3)
    r_m = lm.model.attrs["mesh_frequency"] / lm.model.attrs["input_frequency"]
    cr = modal_crossings(res, r_m, (1.0, 1000.0), harmonics=6, sun_teeth=z_s)
    assert {c.mode_type for c in cr} == {"rotational", "planet"}  # both types are crossed
    for c in cr:
        assert c.excited == (c.mode_type in parker_types(c.harmonic, z_s, N)) == (c.mode_type == "rotational")


def excitation_participation(res, k: int, z_s: int) -> np.ndarray:
    """|phi_i^T F_k| of each mode for the k-th mesh harmonic: planet n's sun-planet and
    planet-ring mesh forces (any common amplitudes and phase between the two) with the phase
    exp(i k z_s psi_n) of its mesh cycle, psi_n its angle; independent of the mode types."""
    sysl = res.system
    g = {s.name: s.g for s in sysl.springs}
    F = sum(np.exp(1j * k * z_s * psi) * (g[f"sun-{p}"] + 0.7 * np.exp(0.3j) * g[f"{p}-ring"])
            for p, psi in zip(sysl.planets, sysl.planet_angles))
    return np.abs(res.shapes.T @ F)


@pytest.mark.parametrize("z_s", [25, 26, 27])
def test_phasing_with_sequentially_phased_planets(z_s):
    """Lin & Parker's 4-planet example (central members translate: rotational, translational and
    planet modes), with a sun of z_s teeth, z_s / N not an integer: each harmonic's crossings are
    excited exactly for the types of Parker's rule (25: f_m and 3 f_m translational, 2 f_m planet
    modes, 4 f_m rotational), and those are the modes the phased mesh forces project on (a mode's
    participation |phi^T F_k| above 1e-3 of the largest where excited, below 1e-9 where not)."""
    res = modes(planetary_system(lin_parker_example(4)))
    cr = modal_crossings(res, 20.0, (1.0, 1000.0), harmonics=8, sun_teeth=z_s)
    assert {c.mode_type for c in cr} == {"rotational", "translational", "planet"}
    for c in cr:
        assert c.excited == (c.mode_type in parker_types(c.harmonic, z_s, 4))
    assert {c.harmonic for c in cr if c.excited and c.mode_type == "translational"} == (
        {1, 3, 5, 7} if z_s % 2 else set())
    for k in range(1, 5):
        p = excitation_participation(res, k, z_s)
        elastic = res.frequencies > 0
        scale = p[elastic].max()
        for i in np.flatnonzero(elastic):
            expected = excites(k, res.mode_type[i], z_s, 4, int(res.harmonic[i]))
            assert (p[i] > 1e-3 * scale) if expected else (p[i] < 1e-9 * scale), (k, i, res.mode_type[i])


def test_campbell_figure(tmp_path):
    res = modes(planetary_system(lin_parker_example(4)))
    fig, cr = fig_campbell(res, 20.0, (5.0, 150.0), sun_teeth=25)
    assert cr and all(5.0 <= c.input_speed <= 150.0 for c in cr)
    assert any(c.excited for c in cr) and not all(c.excited for c in cr)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert "crossing suppressed by planet phasing" in labels
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


def mode_labels(fig):
    """The mode labels of a Campbell figure: text -> window extent (drawn)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    return {t.get_text(): t.get_window_extent(renderer) for t in ax.texts
            if (t.get_gid() or "").startswith("mode-label")}


def test_near_coincident_mode_lines_are_labelled_apart():
    """MERCURY 1-A: the planet pair at 7102.7 Hz and the rotational mode at 7104.3 Hz (1.6 Hz
    apart: one line over the other) each get a label with their mode numbers and frequency at the
    right end, the labels apart (no two overlap), and the dashed planet line is drawn over the
    solid rotational one. Before: no labels, the planet line under the rotational."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config('model = "lumped"\n' + MERCURY)
        lm = build_lumped(cfg)
        res = modes(linearise(lm.model))
    f = res.frequencies
    assert res.mode_type[1:4] == ["planet", "planet", "rotational"] and f[3] - f[1] < 5.0
    r_m = lm.model.attrs["mesh_frequency"] / lm.model.attrs["input_frequency"]
    fig, _ = fig_campbell(res, r_m, (1.0, 200.0), sun_teeth=24)
    labels = mode_labels(fig)
    assert set(labels) == {f"1: {f[0]:.1f} Hz", f"2, 3: {f[1]:.1f} Hz", f"4: {f[3]:.1f} Hz"}
    boxes = list(labels.values())
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
    ax = fig.axes[0]
    line = {round(ln.get_ydata()[0], 2): ln for ln in ax.lines
            if len(ln.get_ydata()) == 2 and ln.get_ydata()[0] == ln.get_ydata()[1] and ln.get_xdata()[0] == 0.0}
    planet, rotational = line[round(f[1], 2)], line[round(f[3], 2)]
    assert planet.get_linestyle() != rotational.get_linestyle() and planet.get_zorder() > rotational.get_zorder()


def test_flexible_campbell_shows_the_mesh_mode_and_the_operating_speed():
    """Flexible spur pair (level 1, shafts): the shaft and load modes lie at 0.1-3.7 kHz, the mesh
    mode near the closed form of two free gears on the mesh spring (far above the shaft modes the
    shafts hold nothing), f = (1/2 pi) sqrt(k_m (r_b1^2 / J_1 + r_b2^2 / J_2 + 1 / m_1 + 1 / m_2))
    with the effective mesh stiffness k_m (14.5 kHz; the mode is 16.6 kHz, the next ones 3.7 and
    57 kHz). The diagram ``flexgear modal`` draws shows
    the mode nearest that formula with its label, reaches it with the 4th harmonic inside the
    speed range, and marks the operating speed (10 Hz). Before: 0-1.6 kHz, the 95 Hz mode only."""
    import tomllib

    from flexgear.config import parse_config
    from flexgear.dynamics.model.assembly import build_model
    from flexgear.results.campbell_plot import modal_campbell

    doc = tomllib.loads(preset_path("spur_pair_flexible").read_text())
    doc["flexible"]["level"] = 1
    cfg = parse_config(doc)
    model = build_model(cfg)
    res = modes(linearise(model, n_positions=4))
    k_m = res.system.attrs["effective_mesh_stiffness"]["pinion-wheel"]
    body = {b.name: b for b in model.bodies}
    pinion, wheel = body["pinion"], body["wheel"]
    f_est = math.sqrt(k_m * (cfg.gears["pinion"].rb ** 2 / pinion.inertia + cfg.gears["wheel"].rb ** 2 / wheel.inertia
                             + 1 / pinion.mass + 1 / wheel.mass)) / (2 * math.pi)
    i = int(np.argmin(np.abs(res.frequencies - f_est)))
    assert res.frequencies[i] > 5e3  # above the shaft modes
    fig, cr = modal_campbell(res, cfg)
    ax = fig.axes[0]
    assert ax.get_ylim()[1] > res.frequencies[i]
    assert any(c.mode == i + 1 and c.harmonic == 4 for c in cr)
    assert f"{i + 1}: {res.frequencies[i]:.1f} Hz" in mode_labels(fig)
    assert "operating speed" in ax.get_legend_handles_labels()[1]
    vertical = [ln for ln in ax.lines if ln.get_xdata()[0] == ln.get_xdata()[-1] == cfg.input_frequency]
    assert vertical
    fig.canvas.draw()  # the legend sits above the axes, off the mode lines it would hide
    assert ax.get_legend().get_window_extent().y0 >= ax.get_window_extent().y1 - 1.0
