"""Tests of flexgear.plots on small synthetic results (sinusoids)."""
import os

import numpy as np
import pytest

from flexgear.errors import ResultExistsError
from flexgear.results.friction_plot import fig_friction, pitch_crossings
from flexgear.results.plots import (characteristic_frequencies, characteristic_lines, fig_mesh_spectrum,
                            is_planetary, mesh_force, paper_figure_names, paper_figures)
from flexgear.results.store import BodySignals, MeshSignals, Result

FS = 5000.0


def _mesh(name, a, b, fn, angle, n, k=2):
    """Mesh whose normal force fn acts along the direction ``angle`` (rad) in the plane."""
    return MeshSignals(
        name=name, body_a=a, body_b=b, normal_force=fn,
        force_global=np.column_stack([fn * np.cos(angle), fn * np.sin(angle)]),
        pair_force=np.column_stack([fn / k] * k), pair_tooth_a=np.zeros((n, k), int),
        pair_tooth_b=np.zeros((n, k), int), pair_side=np.ones((n, k), np.int8),
        penetration=np.full((n, k), 1e-6), attrs={})


def _body(name, t, centre, omega, z=None):
    n = t.size
    return BodySignals(name=name, position=centre, angle=omega * t,
                       velocity=np.gradient(centre, t, axis=0),
                       angular_velocity=np.full(n, omega), torque=None,
                       attrs={} if z is None else {"z": z})


def planetary_result(duration=0.5, with_attrs=True) -> Result:
    """MERCURY 1-A-like kinematics: carrier 8 Hz, mesh 528 Hz, three planets 120 deg apart."""
    t = np.arange(int(duration * FS)) / FS
    fa, fm, rc = 8.0, 528.0, 0.045
    meshes, bodies = {}, {}
    bodies["sun"] = _body("sun", t, np.zeros((t.size, 2)), 2 * np.pi * 30.0, z=24)
    bodies["carrier"] = _body("carrier", t, np.zeros((t.size, 2)), 2 * np.pi * fa)
    bodies["ring"] = _body("ring", t, np.zeros((t.size, 2)), 0.0, z=66)
    for i in range(1, 4):
        theta = 2 * np.pi * fa * t + 2 * np.pi * (i - 1) / 3
        centre = rc * np.column_stack([np.cos(theta), np.sin(theta)])
        bodies[f"planet{i}"] = _body(f"planet{i}", t, centre, -2 * np.pi * 25.14, z=21)
        fn = 236.5 * (1 + 0.05 * np.cos(2 * np.pi * fm * t + 0.4 * i))
        meshes[f"sun-planet{i}"] = _mesh(f"sun-planet{i}", "sun", f"planet{i}", fn,
                                         theta + np.pi / 2 - np.radians(20), t.size)
        meshes[f"planet{i}-ring"] = _mesh(f"planet{i}-ring", f"planet{i}", "ring", fn,
                                          theta + np.pi / 2 + np.radians(20), t.size)
    attrs = {"carrier_frequency": fa, "mesh_frequency": fm} if with_attrs else {}
    return Result(time=0.1 + t, meshes=meshes, bodies=bodies, config_toml="", attrs=attrs)


def spur_result(duration=0.2) -> Result:
    t = np.arange(int(duration * FS)) / FS
    fm = 240.0
    fn = 10140.0 + sum(800.0 / k * np.cos(2 * np.pi * k * fm * t) for k in range(1, 5))
    bodies = {"pinion": _body("pinion", t, np.zeros((t.size, 2)), 2 * np.pi * 10.0, z=24),
              "wheel": _body("wheel", t, np.tile([0.045, 0.0], (t.size, 1)),
                             -2 * np.pi * 10.0 * 24 / 21, z=21)}
    mesh = _mesh("pinion-wheel", "pinion", "wheel", fn, np.radians(90 - 20), t.size)
    mesh.attrs = {"z_a": 24, "z_b": 21, "kind": "external"}
    return Result(time=t, meshes={"pinion-wheel": mesh}, bodies=bodies, config_toml="",
                  attrs={"mesh_frequency": fm, "carrier_frequency": 0.0})


def _png_ok(path):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_paper_figures_planetary(tmp_path):
    r = planetary_result(0.25)
    assert is_planetary(r)
    out = tmp_path / "figs"
    paths = paper_figures(r, out)
    names = [p.name for p in paths]
    assert names == ["fig07_planet_positions.png", "fig08_planet1_ring_force.png",
                     "fig09_planet1_ring_spectrum.png", "fig10_ring_forces_all_planets.png",
                     "fig11_sun_planet1_force.png", "fig12_sun_planet1_spectrum.png"]
    assert names == paper_figure_names("planetary")  # what the CLI checks before running
    assert all(_png_ok(p) for p in paths)
    assert sorted(os.listdir(out)) == sorted(names)  # no temporary files left


def test_paper_figures_spur(tmp_path):
    r = spur_result()
    assert not is_planetary(r)
    paths = paper_figures(r, tmp_path)
    assert [p.name for p in paths] == ["fig03_pinion_wheel_force.png",
                                       "fig04_pinion_wheel_spectrum.png"]
    assert [p.name for p in paths] == paper_figure_names("spur")
    assert all(_png_ok(p) for p in paths)


def sensing(result, noisy=False):
    """``result`` with two synthetic sensors: ``top`` hears the mesh's second harmonic (2 m/s^2)
    and one impulse (30 m/s^2 at 0.1234 s) through the housing, ``ring`` a planet-pass force
    (N) and an acceleration; ``noisy``: each of ring's signals measured with noise whose largest
    peak (40 m/s^2) lies elsewhere, at 0.05 s, the noise-free signal kept beside it."""
    from flexgear.results.noise import NOISE_FREE
    from flexgear.results.store import SensorSignals

    t = result.time
    fm = result.attrs["mesh_frequency"]
    x = 2.0 * np.sin(2 * np.pi * 2 * fm * t) + 30.0 * (np.abs(t - 0.1234) < 0.5 / FS)
    attrs = {"units": "m/s^2", "description": "acceleration through the housing"}
    result.sensors = {
        "top": SensorSignals("top", {"quantity": "acceleration"}, {"housing_path": x}, {"housing_path": attrs}),
        "ring": SensorSignals("ring", {"quantity": "acceleration"},
                              {"housing_path": x, "planet_pass": 100.0 + np.cos(2 * np.pi * fm * t)},
                              {"housing_path": attrs, "planet_pass": {"units": "N", "description": "force"}})}
    if noisy:
        s = result.sensors["ring"]
        for path in list(s.signals):
            s.signals[path + NOISE_FREE] = s.signals[path]
            s.signal_attrs[path + NOISE_FREE] = s.signal_attrs[path]
            s.signals[path] = s.signals[path] + 0.5 * np.random.default_rng(1).standard_normal(t.size) \
                + 40.0 * (np.abs(t - 0.05) < 0.5 / FS)
    return result


def test_noisy_sensor_figure_zooms_where_the_signal_peaks_and_draws_it_over_the_measurement():
    """A noisy sensor: one row per path model as without noise (its noise-free copy is no row
    of its own), the zoom centred on the noise-free signal's impulse (not on the noise's larger
    peak), the noise-free signal drawn over the measured one there."""
    from flexgear.results.sensor_plot import fig_sensor

    r = sensing(spur_result(0.2), noisy=True)
    fig = fig_sensor(r, "ring")
    assert len(fig.axes) == 6
    zoom = fig.axes[1]
    lo, hi = zoom.get_xlim()
    assert lo < 123.4 < hi
    measured, clean = zoom.lines[:2]
    keep = (r.time >= 1e-3 * lo) & (r.time <= 1e-3 * hi)
    assert np.array_equal(clean.get_ydata(), r.sensors["ring"].signals["housing_path_noise_free"][keep])
    assert np.array_equal(measured.get_ydata(), r.sensors["ring"].signals["housing_path"][keep])


def test_sensor_figure_shows_the_record_a_zoom_on_the_impulse_and_the_spectrum(tmp_path):
    """A run with sensors adds ``sensor_<name>.png`` (the names the CLI checks first): per path
    model the record with the zoom window shaded, six mesh periods around the largest deviation
    (the impulse), and the spectrum whose line is the tone's (2 f_m, its amplitude) with every
    k f_m dashed; a path model's force is labelled as one."""
    from flexgear.results.sensor_plot import fig_sensor

    r = sensing(spur_result(0.2))
    paths = paper_figures(r, tmp_path)
    assert [p.name for p in paths] == paper_figure_names("spur", sensors=["top", "ring"])
    assert paths[-2].name == "sensor_top.png" and _png_ok(paths[-2])
    fm = r.attrs["mesh_frequency"]
    fig = fig_sensor(r, "ring")
    assert len(fig.axes) == 6
    record, zoom, spectrum = fig.axes[:3]
    lo, hi = zoom.get_xlim()
    assert (hi - lo) * 1e-3 * fm == pytest.approx(6.0) and lo < 123.4 < hi
    span = next(p for p in record.patches)  # the zoom's window in the record
    assert span.get_x() == pytest.approx(1e-3 * lo) and span.get_width() == pytest.approx(1e-3 * (hi - lo))
    f, a = spectrum.lines[0].get_data()
    # the impulse adds at most 2 x 2 x 30 / n (Hann's amplitude correction) to any line
    assert f[np.argmax(a)] == pytest.approx(2 * fm, abs=f[1]) and a.max() == pytest.approx(2.0, abs=120.0 / r.time.size)
    marks = sorted(line.get_xdata()[0] for line in spectrum.lines[1:])
    assert np.allclose(marks, fm * np.arange(1, len(marks) + 1)) and marks[-1] + fm > FS / 2
    assert fig.axes[3].get_ylabel() == "Force [N]" and record.get_ylabel() == "Acceleration [m/s²]"
    # each row's zoom spans its own window: each is labelled (the top row's was not); the window's
    # edges are drawn in the record, where a few mesh periods of a long record are a sliver
    assert all(fig.axes[k].get_xlabel() == "Time $t$ [ms]" for k in (1, 4))
    assert sorted(ln.get_xdata()[0] for ln in record.lines[1:]) == pytest.approx([1e-3 * lo, 1e-3 * hi])


PITCH = 6.0e-3  # m, base pitch of the synthetic friction records
PATH = (-4.0e-3, 5.5e-3)  # m, start and end of the path of contact (pitch point at 0)


def rubbing(result, film=True) -> Result:
    """``result`` with synthetic friction records on its mesh: pairs a base pitch apart moving
    along the path at one pitch per mesh period (slot j the j-th pair from the start of the path;
    slot 0 passes to the next pair when a pair leaves), the sliding speed proportional to the
    position (0 at the pitch point), so that slot 0 crosses the pitch point at 2/3 of every mesh
    period."""
    t = result.time
    m = result.meshes["pinion-wheel"]
    base = PATH[0] + PITCH * np.mod(t * result.attrs["mesh_frequency"], 1.0)
    s = np.column_stack([base + j * PITCH for j in range(3)])
    s[s > PATH[1]] = np.nan
    m.contact_position = s
    m.sliding_speed = -150.0 * s
    load = np.where(np.isfinite(s), 5000.0, 0.0)
    m.pair_friction_force = 0.05 * load * np.tanh(np.nan_to_num(m.sliding_speed) / 0.01)
    m.friction_force = m.pair_friction_force.sum(axis=1)
    m.friction_power = np.nansum(m.pair_friction_force * m.sliding_speed, axis=1)
    m.attrs["mesh_efficiency"] = 0.99
    if film:
        m.film_ratio = np.where(np.isfinite(s), 0.5 + 100.0 * np.abs(np.nan_to_num(s)), np.nan)
        m.film_minimum = 1e-6 * m.film_ratio
    return result


def test_pitch_crossings_are_where_a_pair_passes_the_pitch_point():
    """Interpolated where a slot's position changes sign (the synthetic pairs: 2/3 of each mesh
    period), not where a slot passes to the next pair (a jump of a base pitch); none without
    friction records."""
    r = spur_result(0.1)
    assert pitch_crossings(r, "pinion-wheel").size == 0
    r = rubbing(r)
    fm = r.attrs["mesh_frequency"]
    want = (np.arange(30) + 2.0 / 3.0) / fm
    want = want[(want > r.time[0]) & (want < r.time[-1])]
    got = pitch_crossings(r, "pinion-wheel")
    assert got.size == want.size == 24
    assert np.allclose(got, want, rtol=0, atol=1e-9)


def test_pair_tracks_follow_each_pair_through_the_slots():
    """The synthetic pairs change slot once per mesh period (slot j holds the j-th pair from the
    start of the path): each track is one pair, sample after sample, its position growing by one
    base pitch per mesh period from where it enters to where it leaves, and the friction figure
    draws one line per pair in panels (b) and (c), in alternating styles."""
    from flexgear.results.friction_plot import pair_tracks

    r = rubbing(spur_result(0.1))
    m = r.meshes["pinion-wheel"]
    tracks = pair_tracks(m.contact_position)
    slot_changes = 0
    for tr in tracks:
        k, c = tr[:, 0], tr[:, 1]
        assert np.all(np.diff(k) == 1)
        s = m.contact_position[k, c]
        step = PITCH * r.attrs["mesh_frequency"] * (r.time[1] - r.time[0])  # per sample
        assert np.allclose(np.diff(s), step)
        slot_changes += int(np.sum(np.diff(c) != 0))
    whole = [tr for tr in tracks if 0 < tr[0, 0] and tr[-1, 0] < r.time.size - 1]
    step = PITCH * r.attrs["mesh_frequency"] * (r.time[1] - r.time[0])
    assert whole and all(m.contact_position[tr[0, 0], tr[0, 1]] - PATH[0] <= step
                         and PATH[1] - m.contact_position[tr[-1, 0], tr[-1, 1]] <= step for tr in whole)
    assert slot_changes >= len(whole)  # every whole passage changed slot at least once
    assert sum(len(tr) for tr in tracks) == np.isfinite(m.contact_position).sum()
    fig = fig_friction(r, "pinion-wheel", periods=r.attrs["mesh_frequency"] * (r.time[-1] - r.time[0]))
    for ax in fig.axes[1:]:
        pairs = [line for line in ax.lines if line.get_linestyle() in ("-", "--") and len(line.get_xdata()) > 2]
        assert len(pairs) == len(tracks)
        assert [line.get_linestyle() for line in pairs] == ["-", "--"] * (len(pairs) // 2) + ["-"] * (len(pairs) % 2)


@pytest.mark.parametrize("film", [True, False])
def test_friction_figure_marks_the_pitch_point_where_the_sliding_reverses(tmp_path, film):
    """A run with friction adds ``friction_<mesh>.png`` to the paper figures (the names the CLI
    checks before running): the friction force, each pair's sliding speed and, with a film, its
    lambda over six mesh periods, the pitch-point crossings dotted in every panel; the sliding
    speed changes sign at each of them."""
    r = rubbing(spur_result(0.2), film=film)
    paths = paper_figures(r, tmp_path)
    assert [p.name for p in paths] == paper_figure_names("spur", friction=True)
    assert paths[-1].name == "friction_pinion_wheel.png" and _png_ok(paths[-1])
    fig = fig_friction(r, "pinion-wheel")
    assert len(fig.axes) == (3 if film else 2)
    lo, hi = fig.axes[0].get_xlim()
    assert (hi - lo) * 1e-3 * r.attrs["mesh_frequency"] == pytest.approx(6.0, rel=0.02)
    want = 1e3 * pitch_crossings(r, "pinion-wheel")
    want = want[(want >= lo) & (want <= hi)]
    assert want.size >= 5
    for ax in fig.axes:
        marks = sorted(line.get_xdata()[0] for line in ax.lines if line.get_linestyle() == ":")
        assert np.allclose(marks, want)
    t_ms, v = 1e3 * r.time, r.meshes["pinion-wheel"].sliding_speed[:, 0]
    for x in want:
        k = int(np.searchsorted(t_ms, x))
        assert v[k - 1] * v[k] < 0


def test_a_figure_saved_outside_the_paper_style_is_the_same_image(tmp_path):
    """matplotlib makes the tick labels and the constrained layout at draw time, from the rc
    parameters then in force: a figure saved with ``fig.savefig`` in a script or notebook under
    the user's own rc (here 14 pt sans-serif at 72 dpi) is the image ``save_figure`` writes, the
    paper style's fonts and 300 dpi."""
    import matplotlib
    from matplotlib.image import imread

    from flexgear.style import save_figure

    r = rubbing(spur_result(0.2), film=True)
    ours = imread(save_figure(fig_friction(r, "pinion-wheel"), tmp_path / "ours.png"))
    with matplotlib.rc_context({"font.size": 14, "font.family": "sans-serif", "savefig.dpi": 72}):
        fig = fig_friction(r, "pinion-wheel")
        fig.savefig(tmp_path / "theirs.png")
    theirs = imread(tmp_path / "theirs.png")
    assert theirs.shape == ours.shape and np.array_equal(theirs[..., :3], ours[..., :3])


@pytest.mark.parametrize("make", ["spur force", "spur spectrum", "planetary force", "planetary spectrum",
                                  "planet positions", "ring forces", "friction", "friction with film", "sensor", "noisy sensor"])
def test_every_text_of_a_paper_figure_lies_on_its_canvas(make):
    """Titles, labels, legends and tick labels of every paper figure stay inside the figure as
    written at 300 dpi (a left-aligned title longer than its axes runs off the right edge)."""
    from flexgear.results.plots import fig_mesh_force, fig_planet_positions, fig_ring_forces
    from flexgear.results.sensor_plot import fig_sensor
    from flexgear.style import DPI, paper_style

    spur, planetary = spur_result(0.2), planetary_result(0.5)
    fig = {"spur force": lambda: fig_mesh_force(spur, "pinion-wheel"),
           "spur spectrum": lambda: fig_mesh_spectrum(spur, "pinion-wheel"),
           "planetary force": lambda: fig_mesh_force(planetary, "planet1-ring"),
           "planetary spectrum": lambda: fig_mesh_spectrum(planetary, "planet1-ring"),
           "planet positions": lambda: fig_planet_positions(planetary),
           "ring forces": lambda: fig_ring_forces(planetary),
           "friction": lambda: fig_friction(rubbing(spur, film=False), "pinion-wheel"),
           "friction with film": lambda: fig_friction(rubbing(spur, film=True), "pinion-wheel"),
           "sensor": lambda: fig_sensor(sensing(spur), "ring"),
           "noisy sensor": lambda: fig_sensor(sensing(spur, noisy=True), "ring")}[make]()
    fig.set_dpi(DPI)
    fig.canvas.draw()
    with paper_style():
        box = fig.get_tightbbox(fig.canvas.get_renderer())  # inches
    width, height = fig.get_size_inches()
    assert box.x0 >= 0.0 and box.y0 >= 0.0 and box.x1 <= width and box.y1 <= height, box


def test_no_mark_on_the_spectrums_right_edge(monkeypatch):
    """At a whole, even number of output samples per mesh period (the spur pair's synchronous
    grid: 42) a mesh harmonic lies on the Nyquist frequency, the spectrum's right edge: it gets
    no mark, whose label would stand beside the axes."""
    import sys

    monkeypatch.setattr(sys.modules[__name__], "FS", 42 * 240.0)
    r = spur_result(0.2)
    fig = fig_mesh_spectrum(r, "pinion-wheel")
    for ax in fig.axes:
        hi = ax.get_xlim()[1]
        marks = [line.get_xdata()[0] for line in ax.lines if line.get_linestyle() == "--"]
        assert marks and max(marks) < hi - 1.0
        assert all(t.get_position()[0] < hi - 1.0 for t in ax.texts if t.get_text().endswith("f_m$"))


def test_paper_figures_refuse_overwrite(tmp_path):
    r = spur_result(duration=0.1)
    paths = paper_figures(r, tmp_path)
    stamps = [os.stat(p).st_mtime_ns for p in paths]
    with pytest.raises(ResultExistsError, match="fig03_pinion_wheel_force.png.*overwrite=True"):
        paper_figures(r, tmp_path)
    assert [os.stat(p).st_mtime_ns for p in paths] == stamps
    assert paper_figures(r, tmp_path, overwrite=True) == paths


def test_characteristic_frequencies_from_attrs_and_kinematics():
    assert characteristic_frequencies(planetary_result(0.25)) == {"carrier": 8.0, "mesh": 528.0}
    fr = characteristic_frequencies(planetary_result(0.25, with_attrs=False))
    assert fr["carrier"] == pytest.approx(8.0) and fr["mesh"] == pytest.approx(528.0)
    r = spur_result(0.1)
    r.attrs = {}
    assert characteristic_frequencies(r)["mesh"] == pytest.approx(240.0)
    labels = [ln.label for ln in characteristic_lines(r)]
    assert labels == ["f_m", "2f_m", "3f_m", "4f_m"]
    assert "f_m-f_a" in [ln.label for ln in characteristic_lines(planetary_result(0.25))]


def test_mesh_force_components():
    r = planetary_result(0.1)
    fy = mesh_force(r, "planet1-ring", "y")
    np.testing.assert_array_equal(fy, r.meshes["planet1-ring"].force_global[:, 1])
    with pytest.raises(ValueError, match="component"):
        mesh_force(r, "planet1-ring", "z")
    with pytest.raises(KeyError, match="planet9-ring"):
        mesh_force(r, "planet9-ring")


def test_spectrum_figure_db_and_no_pyplot_state():
    import matplotlib
    backend = matplotlib.get_backend()
    fig = fig_mesh_spectrum(planetary_result(0.25), "planet1-ring", db=True)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 5  # full range + zooms at f_m .. 4 f_m (all harmonics below 2500 Hz)
    assert visible[0].get_xlim()[1] == pytest.approx(FS / 2)  # the whole output band
    assert matplotlib.get_backend() == backend
    # 0.25 s: 4 Hz bins resolve the 8 Hz carrier sidebands (Hann: two bins); 0.1 s (10 Hz bins) does not
    zooms = visible[1:]
    assert all(ax.get_title(loc="left").endswith(" Hz") for ax in zooms)
    short = [ax for ax in fig_mesh_spectrum(planetary_result(0.1), "planet1-ring", db=True).axes if ax.get_visible()]
    assert all(ax.get_title(loc="left").endswith(" Hz, 10 Hz bins: sidebands not resolved") for ax in short[1:])


def test_spectrum_shows_the_carrier_line_unclipped_and_shades_beyond_the_passband():
    """Issue 6: the 8 Hz line is not clipped, the band above passband_hz is shaded, and the
    legend sits outside the data area."""
    from matplotlib.patches import Rectangle

    r = planetary_result(0.5)
    r.attrs["passband_hz"] = 2000.0
    fig = fig_mesh_spectrum(r, "planet1-ring")
    ax_hi, ax_lo = fig.axes[0], fig.axes[1]
    carrier_peak = 236.5  # N: the vertical component of a force turning with the carrier
    lo, hi = ax_hi.get_ylim()
    assert lo < carrier_peak < hi
    assert ax_lo.get_ylim()[1] < carrier_peak  # the lower panel is scaled to the mesh lines
    for ax in fig.axes[:2]:
        spans = [p for p in ax.patches if isinstance(p, Rectangle)]
        assert any(abs(p.get_x() - 2000.0) < 1e-9 and abs(p.get_x() + p.get_width() - FS / 2) < 1e-9
                   for p in spans)
    leg = fig.axes[0].get_legend()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    assert leg.get_window_extent(renderer).y0 >= ax_hi.get_window_extent(renderer).y1 - 1.0


def test_spectrum_figure_texts_do_not_overlap():
    """No label, note or title of the planetary spectrum figure covers another (the 9 f_m
    marker label once ran into the note in the shaded band)."""
    r = planetary_result(0.5)
    r.attrs["passband_hz"] = 2000.0  # 0.8 x Nyquist: 4 f_m and its markers lie in the shaded band
    fig = fig_mesh_spectrum(r, "planet1-ring", fmax=2112.0 / 0.95)  # 4 f_m near the right edge
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for ax in fig.axes for t in ax.texts
             if t.get_visible() and t.get_text()]
    assert len(boxes) > 10
    for i, (ta, a) in enumerate(boxes):
        for tb, b in boxes[i + 1:]:
            assert not a.overlaps(b), f"{ta!r} overlaps {tb!r}"


def test_a_long_force_trace_gets_a_zoom_on_a_few_mesh_periods_marked_on_it():
    """1 s of a 528 Hz mesh is a solid band at column width: Figs. 8 and 11 get a second panel
    of ZOOM_PERIODS mesh periods (6 / 528 Hz = 11.36 ms) around the largest force, whose window
    is a box on the full trace; Fig. 3's 0.06 s of the spur pair (14 periods) stays one panel."""
    from matplotlib.patches import Rectangle

    from flexgear.results.plots import fig_mesh_force
    from flexgear.style import ZOOM_PERIODS

    r = planetary_result(1.0)
    r.meshes["planet1-ring"].force_global[:, 1] *= 1 + 0.3 * np.sin(2 * np.pi * 8.0 * r.time)  # an envelope
    fig = fig_mesh_force(r, "planet1-ring")
    ax, axz = fig.axes
    z0, z1 = axz.get_xlim()
    assert ZOOM_PERIODS == 6 and z1 - z0 == pytest.approx(6 / 528.0, rel=1e-9)
    assert ax.get_xlim()[1] - ax.get_xlim()[0] > 0.99  # the full trace above it
    fy = np.abs(r.meshes["planet1-ring"].force_global[:, 1])
    assert z0 <= r.time[np.argmax(fy)] <= z1  # where the mesh ripple is largest
    boxes = [p for p in ax.patches if isinstance(p, Rectangle)]
    assert any(p.get_x() == pytest.approx(z0) and p.get_x() + p.get_width() == pytest.approx(z1) for p in boxes)
    lo, hi = axz.get_ylim()
    inside = r.meshes["planet1-ring"].force_global[(r.time >= z0) & (r.time <= z1), 1]
    assert lo <= inside.min() and inside.max() <= hi  # the box spans what the zoom shows
    assert ax.get_xlabel() == axz.get_xlabel() == "Time $t$ [s]"  # two time ranges: each panel its axis label
    assert len(fig_mesh_force(spur_result(0.2), "pinion-wheel", duration=0.06).axes) == 1
    assert len(fig_mesh_force(r, "planet1-ring", zoom=False).axes) == 1


def _extents(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def test_spectrum_title_and_legend_take_a_line_each_and_the_carrier_line_clears_the_spine():
    """The title and the legend under it do not share a line (their heights do not overlap);
    the carrier line at 8 Hz stands clear of the axis spine (a range from 0 Hz starts a little
    below 0) and its label lies inside the panel."""
    r = planetary_result(0.5)
    r.attrs["passband_hz"] = 2000.0
    s = spur_result(0.2)
    s.attrs["passband_hz"] = 2000.0
    for fig in (fig_mesh_spectrum(r, "planet1-ring"), fig_mesh_spectrum(s, "pinion-wheel")):
        renderer = _extents(fig)
        top = fig.axes[0]
        title = top.title if top.title.get_text() else top._left_title
        t, leg = title.get_window_extent(renderer), top.get_legend().get_window_extent(renderer)
        assert t.y0 >= leg.y1 or leg.y0 >= t.y1, (t, leg)
        assert leg.y0 >= top.get_window_extent(renderer).y1 - 1.0  # and neither over the data
    fig = fig_mesh_spectrum(r, "planet1-ring")
    renderer = _extents(fig)
    top = fig.axes[0]
    box = top.get_window_extent(renderer)
    x_line = top.transData.transform((8.0, 0.0))[0]
    assert x_line - box.x0 >= 5.0  # pixels at 100 dpi: apart from the spine
    label = next(t for t in top.texts if t.get_text() == "$f_a$")
    assert label.get_window_extent(renderer).x0 >= box.x0 + 1.0


def test_spur_spectrum_note_covers_no_marker_label_or_line():
    """A 10 kHz spur spectrum to 20 f_m with the band above 4 kHz shaded: its 17-20 f_m markers
    lie in the band; no text (marker labels, a band note) overlaps another or a marker line."""
    from matplotlib.lines import Line2D

    fs, fm = 10000.0, 240.0
    t = np.arange(int(0.5 * fs)) / fs
    fn = 10140.0 + sum(800.0 / k * np.cos(2 * np.pi * k * fm * t) for k in range(1, 21))
    s = spur_result(0.5)
    mesh = _mesh("pinion-wheel", "pinion", "wheel", fn, np.radians(70.0), t.size)
    s = Result(time=t, meshes={"pinion-wheel": mesh}, bodies=s.bodies, config_toml="",
               attrs={"mesh_frequency": fm, "carrier_frequency": 0.0, "passband_hz": 4000.0})
    fig = fig_mesh_spectrum(s, "pinion-wheel")
    renderer = _extents(fig)
    ax = fig.axes[0]
    texts = [(x.get_text(), x.get_window_extent(renderer)) for x in ax.texts if x.get_visible() and x.get_text()]
    assert sum("f_m" in name for name, _ in texts) == 20
    markers = [ln.get_window_extent(renderer) for ln in ax.lines if isinstance(ln, Line2D)
               and ln.get_linestyle() == "--"]
    assert len(markers) == 20
    for i, (na, a) in enumerate(texts):
        for nb, b in texts[i + 1:]:
            assert not a.overlaps(b), f"{na!r} overlaps {nb!r}"
        assert not any(a.overlaps(m) for m in markers), f"{na!r} covers a marker line"


def test_a_faulty_result_zooms_on_a_fault_event():
    """MERCURY 1-A (lumped, the presets' 1 s) with a cracked sun tooth: the zoom of Figs. 8 and
    11 sits on the crack's largest event, where the faulty run departs most from the healthy
    one (not simulated for the figure: found here from both runs; within 0.8 of the largest
    departure, where the largest force's window reaches 0.57-0.65), and says so; a healthy
    run's zoom stays on its largest force."""
    import math

    import flexgear
    from flexgear.config import load_config
    from flexgear.gears.faults import Crack
    from matplotlib.text import Text

    from flexgear.results.plots import fig_mesh_force

    runs = []
    for faults in ((), (Crack(gear="sun", tooth=0, flank="left", depth=1.5e-3, angle=math.radians(45)),)):
        cfg = load_config("mercury_1a")
        cfg.model = "lumped"
        cfg.faults = faults
        runs.append(flexgear.run(cfg))
    healthy, faulty = runs
    t = np.asarray(faulty.time)
    for mesh in ("sun-planet1", "planet1-ring"):
        f = faulty.meshes[mesh].force_global[:, 1]
        d = np.abs(f - healthy.meshes[mesh].force_global[:, 1])
        fig = fig_mesh_force(faulty, mesh)
        z0, z1 = fig.axes[1].get_xlim()
        assert d[(t >= z0) & (t <= z1)].max() > 0.8 * d.max(), mesh  # the largest event in the zoom
        assert "fault event" in fig.axes[1].get_title(loc="left")
        fig.canvas.draw()
        title = [c for c in fig.axes[1].get_children() if isinstance(c, Text) and c.get_text().startswith("(b)")]
        assert title[0].get_window_extent().x1 <= fig.bbox.x1  # the title fits
        marks = [ln.get_xdata()[0] for ln in fig.axes[1].lines if ln.get_linestyle() == "--"]
        assert len(marks) == 1 and d[np.abs(t - marks[0]) <= 1.0 / 528.0].max() > 0.8 * d.max(), mesh
        hz0, hz1 = fig_mesh_force(healthy, mesh).axes[1].get_xlim()  # healthy: the largest force
        assert hz0 <= t[np.argmax(np.abs(healthy.meshes[mesh].force_global[:, 1]))] <= hz1


def test_the_spur_fig3_window_holds_a_faults_event_and_marks_it(tmp_path, monkeypatch):
    """The paper's Fig. 3 shows 0.06 s of the record; a faulty result's window is centred on its
    largest fault event instead of the record's start (a trial: a missing tooth meshing at 0.296 s
    of a 0.3 s record was outside the figure, which showed 0.20-0.26 s), the event dashed; the
    window holds where the faulty force departs most from the healthy one. A healthy result keeps
    the paper's window from the start."""
    import flexgear
    import flexgear.results.plots as plots

    def run(preset):
        cfg = flexgear.load_config(preset)
        cfg.simulation.update(run_in=0.1, duration=0.3)
        return flexgear.run(cfg)

    healthy, missing = run("spur_pair"), run("spur_pair_missing_tooth")
    seen = []
    real = plots.fig_mesh_force

    def spy(result, mesh, **kw):
        seen.append(kw)
        return real(result, mesh, **kw)

    monkeypatch.setattr(plots, "fig_mesh_force", spy)
    for res, out in ((healthy, tmp_path / "h"), (missing, tmp_path / "m")):
        plots.paper_figures(res, out)
    assert seen[0]["t_start"] is None and seen[0]["duration"] == 0.06
    t0 = seen[1]["t_start"]
    f_h, f_m = (mesh_force(r, "pinion-wheel", "y") for r in (healthy, missing))
    worst = missing.time[int(np.argmax(np.abs(f_m - f_h)))]  # a passage of the missing tooth
    turn = 1.0 / missing.attrs["input_frequency"]  # it passes once per pinion turn
    fm = characteristic_frequencies(missing)["mesh"]
    lag = (t0 + 0.03 - worst) / turn
    assert t0 > missing.time[0] and abs(lag - round(lag)) * turn < 2.0 / fm, (t0, worst)
    ax = real(missing, "pinion-wheel", t_start=t0, duration=0.06).axes[0]
    assert "a fault event (dashed)" in ax.get_title(loc="left")
    assert any(ln.get_linestyle() == "--" and t0 <= ln.get_xdata()[0] <= t0 + 0.06 for ln in ax.lines)
