"""EHL film thickness outputs of lubricated runs (issue 24, flexgear.results.film): the recorded
film at the pitch point of a slowly turned spur pair equals the line-contact formula evaluated
independently from the nominal kinematics (the pitch radii, the drive speed and the load torque,
not the recorded positions and speeds), lambda = h_min / composite roughness, the datasets
round-trip through the result file, and a run without a lubricant has none.

At the pitch point the relative radius is R = r_w1 r_w2 sin(a_w) / (r_w1 + r_w2) and both
flanks move at u_e = omega_1 r_w1 sin(a_w); with one pair in contact there it carries
N = T_2 / r_b2 (the friction force vanishes with the sliding speed)."""
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.app.metrics import DEFAULT_METRICS, compute_metrics
from flexgear.config import loads_config, preset_path
from flexgear.config.faults import mesh_pairs
from flexgear.gears.lubrication import ideal_pair_loads
from flexgear.gears.material import effective_modulus
from flexgear.gears.tribology import central_film_thickness, minimum_film_thickness
from flexgear.results.store import load, save, validate

T_LOAD = 200.0  # N m on the spur preset's wheel
SPEED = 2.0  # Hz, pinion
ETA, ALPHA = 0.05, 2.0e-8
RQ = {"pinion": 0.3e-6, "wheel": 0.4e-6}
LUB = (f"friction_coefficient = 0.05\nviscosity = {ETA}\npressure_viscosity = {ALPHA}\n"
       f"[lubrication.gear_roughness]\npinion = {RQ['pinion']}\nwheel = {RQ['wheel']}\n")
SPUR = preset_path("spur_pair").read_text().replace("speed_hz = 10.0", f"speed_hz = {SPEED}")
TEXT = {
    # the preset's contact stiffened 100 times: close to rigid involutes (tests/test_rigid_friction.py)
    "rigid": SPUR.replace("stiffness = 3.0e5", "stiffness = 3.0e7"),
    # the lumped spur pair with damping_ratio instead of the ADAMS damper (tests/test_lumped_friction.py)
    "lumped": ('model = "lumped"\n' + SPUR).replace("damping = 3000.0 ", "damping_ratio = 0.05 "),
}


def _run(model, lub=LUB):
    cfg = loads_config(TEXT[model] + "\n[lubrication]\n" + lub)
    cfg.simulation.update(run_in=0.15, duration=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return cfg, flexgear.run(cfg)


@pytest.mark.parametrize("model", ["rigid", "lumped"])
def test_film_at_the_pitch_point_is_the_formula(model, tmp_path):
    cfg, res = _run(model)
    validate(res)
    m = res.meshes["pinion-wheel"]
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    # nominal kinematics at the pitch point
    aw = pair.alpha_w
    r1, r2 = pair.g1.rb / math.cos(aw), pair.g2.rb / math.cos(aw)
    R = r1 * r2 * math.sin(aw) / (r1 + r2)
    ue = 2 * math.pi * SPEED * r1 * math.sin(aw)
    pairs_at_pitch = np.count_nonzero(ideal_pair_loads(pair, np.array([0.0]), 1.0)[0])
    assert pairs_at_pitch == 1
    w = T_LOAD / pair.g2.rb / min(pair.g1.face_width, pair.g2.face_width)
    e_star = effective_modulus(cfg.material, cfg.material)
    want = {"film_central": central_film_thickness(ue, ETA, ALPHA, w, R, e_star),
            "film_minimum": minimum_film_thickness(ue, ETA, ALPHA, w, R, e_star)}
    assert 1e-8 < want["film_minimum"] < want["film_central"] < 1e-6  # a thin EHL film, slow and loaded
    # the recorded film near the pitch point, interpolated to s = 0 by a straight-line fit
    s = m.contact_position
    for f, h in want.items():
        rec = getattr(m, f)
        near = np.isfinite(rec) & (np.abs(s) < 0.3e-3)
        assert near.sum() >= 10
        got = np.polyval(np.polyfit(s[near], rec[near], 1), 0.0)
        assert got == pytest.approx(h, rel=0.01), f
    # lambda: h_min over the composite roughness of the two gears
    on = np.isfinite(m.film_minimum)
    assert np.array_equal(on, np.isfinite(m.film_ratio))
    assert np.allclose(m.film_ratio[on], m.film_minimum[on] / math.hypot(*RQ.values()), rtol=1e-12)
    # no film where there is no pair
    assert np.all(np.isnan(m.film_central[np.isnan(s)]))
    back = load(save(res, tmp_path / "film.h5")).meshes["pinion-wheel"]
    for f in ("film_central", "film_minimum", "film_ratio"):
        assert np.array_equal(getattr(back, f), getattr(m, f), equal_nan=True)
    # what the film came from, in the file for a check by hand: the given lubricant, the Hertz
    # modulus of two equal steels E / (2 (1 - nu^2)) and the composite roughness
    mat = cfg.material
    assert back.attrs["film_viscosity"] == ETA and back.attrs["film_pressure_viscosity"] == ALPHA
    assert back.attrs["film_effective_modulus"] == pytest.approx(mat.E / (2 * (1 - mat.nu ** 2)), rel=1e-12)
    assert back.attrs["film_roughness"] == pytest.approx(math.hypot(*RQ.values()), rel=1e-12)


def test_no_film_without_a_lubricant(tmp_path):
    """The constant coefficient without a viscosity: friction outputs, no film."""
    _, res = _run("lumped", "friction_coefficient = 0.05\n")
    m = res.meshes["pinion-wheel"]
    assert m.friction_force is not None
    assert m.film_central is None and m.film_minimum is None and m.film_ratio is None
    back = load(save(res, tmp_path / "nofilm.h5")).meshes["pinion-wheel"]
    assert back.film_central is None and "film_viscosity" not in back.attrs


@pytest.mark.parametrize("lumped", [True, False])
def test_film_slots_share_the_load_as_the_model_does(lumped):
    """One row per case: the lumped model's mesh force is shared equally by the pairs on the
    path of contact, on the drive flank only (pair_side of column 0); the rigid model's slots
    carry their own force; nan for no pair, no load or the back flank."""
    from flexgear.results.film import FilmMesh, film_slots
    mesh = FilmMesh(arm_a=0.01, arm_b=0.03, sigma=1.0, width=0.02, eta=ETA, alpha=ALPHA, e_star=1.1e11,
                    start=-0.01, end=0.01)
    nan = np.nan
    s = np.array([[-1e-3, 2e-3, nan], [-1e-3, 2e-3, nan], [5e-4, nan, nan], [5e-4, nan, nan]])
    force = np.array([[800.0, 300.0, 0.0], [800.0, 300.0, 0.0], [-50.0, 0.0, 0.0], [600.0, 0.0, 0.0]])
    side = np.array([[1, 1, 0], [-1, -1, 0], [1, 0, 0], [1, 0, 0]], np.int8)
    wa, wb = np.full(4, 300.0), np.full(4, -100.0)
    hc, hm = np.empty(s.shape), np.empty(s.shape)
    film_slots(s, force, side, wa, wb, mesh, lumped, hc, hm)

    def expected(si, N):
        ra, rb = 0.01 + si, 0.03 - si
        R, ue = ra * rb / (ra + rb), 0.5 * (300.0 * ra + 100.0 * rb)
        return (central_film_thickness(ue, ETA, ALPHA, N / 0.02, R, 1.1e11),
                minimum_film_thickness(ue, ETA, ALPHA, N / 0.02, R, 1.1e11))

    if lumped:  # row 0: 800 N shared by two pairs; row 1: back flank; row 2: no load; row 3: one pair
        want = {(0, 0): 400.0, (0, 1): 400.0, (3, 0): 600.0}
    else:  # the slots' own forces; the back flank's slots carry theirs too (the rigid model records them)
        want = {(0, 0): 800.0, (0, 1): 300.0, (1, 0): 800.0, (1, 1): 300.0, (3, 0): 600.0}
    for (i, j), N in want.items():
        c, m = expected(s[i, j], N)
        assert hc[i, j] == pytest.approx(c, rel=1e-13) and hm[i, j] == pytest.approx(m, rel=1e-13)
    loaded = np.zeros(s.shape, bool)
    loaded[tuple(np.array(list(want)).T)] = True
    assert np.all(np.isnan(hc[~loaded])) and np.all(np.isnan(hm[~loaded]))


def test_pair_speeds_is_the_recorded_sliding_speed():
    """flexgear.gears.lubrication.pair_speeds, the public helper of the guide's Python snippet,
    gives the sliding speed of the results (sign and value): at every recorded contact on the
    path of contact of the slowly turned spur pair (rigid model, stiff contact),
    pair_speeds(pair, s, omega_1) with the recorded contact position and pinion speed equals the
    recorded ``sliding_speed`` within 2 % of its largest value (measured 0.8 %: the wheel's
    vibration about the nominal ratio, which the helper's rigid turning leaves out), and the
    friction force has the helper's sign away from the pitch point (mu(v_s) signed like
    pair_friction_force / pair_force)."""
    from flexgear.gears.lubrication import pair_speeds

    cfg, res = _run("rigid")
    m = res.meshes["pinion-wheel"]
    pair = mesh_pairs(cfg)["pinion-wheel"][2]
    gf, ga = pair.path_of_contact
    s = m.contact_position
    on = np.isfinite(s) & (s > -gf) & (s < ga)
    w1 = np.broadcast_to(res.bodies["pinion"].angular_velocity[:, None], s.shape)
    vs, _ = pair_speeds(pair, s[on], w1[on])
    rec = m.sliding_speed[on]
    assert np.max(np.abs(vs - rec)) < 0.02 * np.max(np.abs(rec))
    fast = np.abs(vs) > 5 * cfg.lubrication.sliding_speed_scale
    assert fast.sum() > 100
    assert np.all(np.sign(m.pair_friction_force[on][fast]) == np.sign(vs[fast]))


def _dowson_higginson(u_e, eta, alpha, w, R, e_star):
    """h_min = 2.65 R U^0.70 G^0.54 W^-0.13 [m] (Dowson & Higginson 1977), E' = 2 E*, written out
    here (not flexgear's kernel)."""
    e1 = 2.0 * e_star
    return 2.65 * R * (eta * u_e / (e1 * R)) ** 0.70 * (alpha * e1) ** 0.54 * (w / (e1 * R)) ** -0.13


def _involute_ends(pair):
    """(s_start, s_end) [m] of an internal pair (planet-ring) from the tip and form circles,
    each flank's involute radius of curvature rho = sqrt(r^2 - r_b^2): the planet's rho_1 =
    r_b1 tan a_w + s from its form to its tip circle, the ring's rho_2 = r_b2 tan a_w + s from
    its tip circle (inside) to its form circle (outside)."""
    g1, g2 = pair.g1, pair.g2
    t = math.tan(pair.alpha_w)

    def rho(g, r):
        return math.sqrt(r * r - g.rb * g.rb)

    return (max(rho(g1, g1.r_form) - g1.rb * t, rho(g2, g2.ra) - g2.rb * t),
            min(rho(g1, g1.ra) - g1.rb * t, rho(g2, g2.r_form) - g2.rb * t))


def test_no_line_contact_film_past_the_tip():
    """A contact outside the involute of either flank (MERCURY 1-A's planet-ring pair: the ring's
    tip corner on the planet's flank at s = -5.99 mm, where the ring's involute would have a
    radius of curvature below its tip circle's and the planet's point lies below its form circle)
    gets no line-contact film (nan) and is counted; one at the end of the path of contact gets
    Dowson & Higginson's film from the involutes' radii of curvature there. The involute limits
    are the ISO path of contact (-g_f, g_a) for these gears."""
    from flexgear.gears.lubrication import involute_contact_limits
    from flexgear.results.film import film_mesh, film_slots

    cfg = flexgear.load_config("mercury_1a_friction")
    pair = mesh_pairs(cfg)["planet1-ring"][2]
    start, end = _involute_ends(pair)
    gf, ga = pair.path_of_contact
    assert start == pytest.approx(-gf, abs=1e-12) and end == pytest.approx(ga, abs=1e-12)
    assert involute_contact_limits(pair) == pytest.approx((start, end), abs=1e-12)
    e_star = effective_modulus(cfg.material, cfg.material)
    mesh = film_mesh(pair, ETA, ALPHA, e_star)
    s = np.array([[-5.99e-3, start + 1e-7, end + 2e-7, end - 1e-7]])
    force, side = np.full(s.shape, 100.0), np.ones(s.shape, np.int8)
    wa, wb = np.array([150.0]), np.array([50.0])
    hc, hm = np.empty(s.shape), np.empty(s.shape)
    corners = film_slots(s, force, side, wa, wb, mesh, False, hc, hm)
    assert corners == 2
    assert np.isnan(hc[0, [0, 2]]).all() and np.isnan(hm[0, [0, 2]]).all()
    t = math.tan(pair.alpha_w)
    for j in (1, 3):
        rho1, rho2 = pair.g1.rb * t + s[0, j], pair.g2.rb * t + s[0, j]
        R, ue = rho1 * rho2 / (rho2 - rho1), 0.5 * (150.0 * rho1 + 50.0 * rho2)
        want = _dowson_higginson(ue, ETA, ALPHA, 100.0 / pair.face_width, R, e_star)
        assert hm[0, j] == pytest.approx(want, rel=1e-12)


def test_least_film_of_a_run_is_that_of_the_path_of_contact():
    """mercury_1a_friction, rigid, with its soft contact, whose loaded tip corners touch outside
    the ISO path of contact: every loaded contact outside it has no film and is counted in
    ``film_corner_contacts``; the least lambda of the planet-ring mesh is Dowson & Higginson's
    film over the roughness worked out here from the gear geometry at the recorded involute
    contacts (their positions and normal forces, the nominal speeds relative to the carrier:
    2 %, the vibration's speed fluctuation), it lies on the path of contact, and no involute
    contact is thinner than that formula at the approach end of the path (the ring's tip, the
    smallest relative radius and entrainment speed) at the largest recorded contact force."""
    cfg = flexgear.load_config("mercury_1a_friction")
    cfg.simulation.update(run_in=0.2, duration=0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = flexgear.run(cfg)
    m = res.meshes["planet1-ring"]
    pair = mesh_pairs(cfg)["planet1-ring"][2]
    start, end = _involute_ends(pair)
    s, N = m.contact_position, m.pair_force
    loaded = np.isfinite(s) & (N > 0)
    outside = loaded & ((s < start) | (s > end))
    assert outside.sum() > 0 and np.all(np.isnan(m.film_ratio[outside]))
    assert m.attrs["film_corner_contacts"] == outside.sum()
    assert np.all(np.isfinite(m.film_ratio[loaded & ~outside]))
    values, _ = compute_metrics(res, DEFAULT_METRICS)  # the batch summary's count
    assert values["film_corner_contacts_planet1_ring"] == outside.sum()
    # independent: nominal kinematics relative to the carrier, mesh frequency z_r f_c
    zs, zp, zr = (cfg.gears[g].z for g in ("sun", "planet", "ring"))
    f_mesh = zr * cfg.drive["speed_hz"] * zs / (zs + zr)
    w1, w2 = 2 * math.pi * f_mesh / zp, 2 * math.pi * f_mesh / zr
    t = math.tan(pair.alpha_w)
    oil, rq = cfg.lubrication.lubricant, cfg.lubrication.roughness
    e_star = cfg.material.E / (2 * (1 - cfg.material.nu ** 2))

    def lam(si, Ni):
        rho1, rho2 = pair.g1.rb * t + si, pair.g2.rb * t + si
        R, ue = rho1 * rho2 / (rho2 - rho1), 0.5 * (w1 * rho1 + w2 * rho2)
        return _dowson_higginson(ue, oil.viscosity, oil.pressure_viscosity, Ni / pair.face_width, R, e_star) / rq

    on = loaded & ~outside
    want = lam(s[on], N[on])
    got = np.nanmin(m.film_ratio)
    assert got == pytest.approx(want.min(), rel=0.02)
    assert start <= s.flat[np.nanargmin(m.film_ratio)] <= end
    assert got >= lam(start, N[on].max())


def test_summary_columns_give_the_loss_the_efficiency_implies():
    """The friction and film columns of a lubricated run's batch summary (flexgear.app.metrics)
    and of ``flexgear run``'s summary: the friction loss is what the mesh efficiency leaves of
    the output power, (1/eta - 1) T_2 omega_2 with the applied torque and the nominal wheel speed
    (1 %: the window's mean of the filtered friction power against the efficiency's sums over
    its steps), lambda's least value is the thinnest film over the composite roughness; a run
    without [lubrication] has none of these columns and no friction table."""
    from flexgear.app.cli import summary_text

    cfg, res = _run("lumped")
    values, info = compute_metrics(res, DEFAULT_METRICS)
    m = res.meshes["pinion-wheel"]
    eta = values["mesh_efficiency_pinion_wheel"]
    assert eta == m.attrs["mesh_efficiency"] and 0.95 < eta < 1.0
    assert "contact_pairs_mean_pinion_wheel" not in values  # a lumped run's slots hold the mesh's force
    z1, z2 = (g.z for g in (cfg.gears["pinion"], cfg.gears["wheel"]))
    omega2 = 2 * math.pi * SPEED * z1 / z2
    assert values["friction_loss_pinion_wheel"] == pytest.approx((1.0 / eta - 1.0) * T_LOAD * omega2, rel=0.01)
    assert values["rms_friction_force_pinion_wheel"] == pytest.approx(np.sqrt(np.mean(m.friction_force**2)))
    film = values["min_film_pinion_wheel"]
    assert film == np.nanmin(m.film_minimum) and 1e-9 < film < 1e-6
    assert values["min_film_ratio_pinion_wheel"] == pytest.approx(film / math.hypot(*RQ.values()), rel=1e-12)
    assert values["film_corner_contacts_pinion_wheel"] == 0  # a lumped mesh's pairs stay on the path
    assert [info[f"{k}_pinion_wheel"][0] for k in ("mesh_efficiency", "friction_loss", "min_film")] == ["1", "W", "m"]
    row = next(line for line in summary_text(res).splitlines() if line.startswith("| pinion-wheel") and "." in line
               and f"{100 * eta:.3f}" in line)
    assert f"{values['friction_loss_pinion_wheel']:.4g}" in row and f"{film * 1e6:.3g}" in row
    assert "film_damping_loss_pinion_wheel" not in values and "film damping" not in summary_text(res)
    # the squeeze film's loss: a column and a cell of its own, its mean damping power
    _, res = _run("lumped", 'damping = "squeeze_film"\n' + LUB)
    values, info = compute_metrics(res, DEFAULT_METRICS)
    loss = values["film_damping_loss_pinion_wheel"]
    assert loss == pytest.approx(np.mean(res.meshes["pinion-wheel"].damping_power)) and loss > 0
    assert info["film_damping_loss_pinion_wheel"][0] == "W"
    lines = summary_text(res).splitlines()
    h = next(i for i, line in enumerate(lines) if "film damping W" in line)
    head, row = ([c.strip() for c in lines[k].strip("|").split("|")] for k in (h, h + 2))
    assert row[0] == "pinion-wheel" and row[head.index("film damping W")] == f"{loss:.4g}"
    # without [lubrication]
    cfg = loads_config(TEXT["lumped"])
    cfg.simulation.update(run_in=0.15, duration=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dry = flexgear.run(cfg)
    values, _ = compute_metrics(dry, DEFAULT_METRICS)
    assert "mean_force_pinion_wheel" in values
    assert not [k for k in values if "friction" in k or "film" in k or "efficiency" in k]
    assert "efficiency" not in summary_text(dry)


@pytest.mark.parametrize("preset", ["spur_pair", "mercury_1a"])
def test_info_gives_the_nominal_efficiency_and_pitch_point_film(preset):
    """``flexgear info`` of a lubricated configuration: per pair the efficiency of a constant
    coefficient is 1 - mu H_V (the closed form; 1 % of the loss: the regularisation near the
    pitch point), and the pitch point's film is the line-contact formula at the kinematics and
    load worked out here independently: the pitch radii, the speed of gear 1 relative to the
    carrier and the static tooth force from the load torque (to the 4 digits printed)."""
    from flexgear.app.cli import info_text
    from flexgear.gears.lubrication import loss_factor

    text = preset_path(preset).read_text()
    if preset == "spur_pair":
        text = text.replace("speed_hz = 10.0", f"speed_hz = {SPEED}")
        lub = LUB
    else:  # the gears' roughness by their [gears] names
        lub = (LUB.split("[lubrication.gear_roughness]")[0]
               + "[lubrication.gear_roughness]\nsun = 0.3e-6\nplanet = 0.4e-6\nring = 0.5e-6\n")
    cfg = loads_config(text + "\n[lubrication]\n" + lub)
    info = info_text(cfg)
    e_star = effective_modulus(cfg.material, cfg.material)
    f_in = cfg.input_frequency
    for name, pair in cfg.pairs.items():
        section = info.split("## Lubrication")[1].split("\n## ")[0]
        row = next(line for line in section.splitlines() if line.startswith(f"| {name} "))
        cells = [c.strip() for c in row.split("|")[1:-1]]
        # the closed form for a constant coefficient
        assert float(cells[1]) == pytest.approx(loss_factor(pair), rel=1e-3)
        assert 1.0 - float(cells[2]) / 100.0 == pytest.approx(0.05 * loss_factor(pair), rel=0.01)
        # the pitch point's film from the kinematics and load worked out here
        aw = pair.alpha_w
        r1, r2 = pair.g1.rb / math.cos(aw), pair.g2.rb / math.cos(aw)
        R = r1 * r2 * math.sin(aw) / ((r2 - r1) if pair.internal else (r1 + r2))
        if cfg.kind == "spur":
            omega1 = 2 * math.pi * f_in  # the pinion is driven
            F = T_LOAD / pair.g2.rb
        else:
            zs, zr = cfg.gears["sun"].z, cfg.gears["ring"].z
            f_rel = f_in * zr / (zs + zr)  # the sun relative to the carrier (the sun driven, the ring held)
            omega1 = 2 * math.pi * f_rel * (1.0 if name.startswith("sun") else zs / pair.g1.z)
            F = cfg.load["torque"] / (1 + zr / zs) / cfg.planetary["planets"] / cfg.gears["sun"].rb
        ue = omega1 * r1 * math.sin(aw)
        w = F / pair.face_width
        want = minimum_film_thickness(ue, ETA, ALPHA, w, R, e_star)
        assert float(cells[3]) == pytest.approx(w, rel=1e-3)
        assert float(cells[5]) == pytest.approx(1e6 * want, rel=1e-3)
        assert float(cells[4]) == pytest.approx(1e6 * central_film_thickness(ue, ETA, ALPHA, w, R, e_star), rel=1e-3)
        rq = cfg.lubrication.mesh_roughness(pair.g1.name, pair.g2.name)
        assert float(cells[6]) == pytest.approx(want / rq, rel=1e-3)


def test_info_says_why_it_has_no_nominal_values_under_a_load_table():
    """A load torque given as a table has no static load: the lubrication section names the
    model and says so, with no table of made-up values."""
    from flexgear.app.cli import info_text

    text = preset_path("spur_pair").read_text().replace("torque = 200.0", "torque = [[0.0, 100.0], [1.0, 200.0]]")
    assert "[[0.0, 100.0]" in text
    info = info_text(loads_config(text + "\n[lubrication]\n" + LUB)).split("## Lubrication")[1].split("\n## ")[0]
    assert "constant mu = 0.05" in info and "no static load" in info and "| H_V" not in info


def test_info_says_its_efficiency_is_the_iso_path_closed_form():
    """``flexgear info`` says that its efficiency is the closed form over the ISO path of contact
    and that a rigid run, whose soft contact touches beyond that path, loses more; a lumped
    configuration's says its pairs stay on the path. Checked against a run: the rigid spur pair
    with mu = 0.05 has contacts outside the ISO path (-g_f, g_a) and an efficiency below 1 - mu H_V,
    H_V = pi (u + 1) / (z_1 u) (1 - eps + eps_1^2 + eps_2^2) written out here."""
    from flexgear.app.cli import info_text

    text = preset_path("spur_pair").read_text() + "\n[lubrication]\nfriction_coefficient = 0.05\n"
    cfg = loads_config(text)
    section = info_text(cfg).split("## Lubrication")[1].split("\n## ")[0]
    assert "closed form over the ISO 21771 path of contact" in section and "loses more" in section
    assert "Mesh losses and efficiency" in section
    lumped = loads_config('model = "lumped"\n' + text.replace("damping = 3000.0 ", "damping_ratio = 0.05 "))
    assert "stay on that path" in info_text(lumped).split("## Lubrication")[1]
    pair = cfg.pairs["pinion-wheel"]
    gf, ga = pair.path_of_contact
    z1, z2 = pair.g1.z, pair.g2.z
    u, e1, e2 = z2 / z1, ga / pair.g1.pb, gf / pair.g1.pb
    hv = math.pi * (u + 1) / (z1 * u) * (1 - (e1 + e2) + e1 ** 2 + e2 ** 2)
    row = next(line for line in section.splitlines() if line.startswith("| pinion-wheel"))
    assert float(row.split("|")[3]) == pytest.approx(100 * (1 - 0.05 * hv), abs=0.002)
    cfg.simulation.update(run_in=0.15, duration=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = flexgear.run(cfg)
    m = res.meshes["pinion-wheel"]
    assert np.nanmin(m.contact_position) < -gf - 1e-4 and np.nanmax(m.contact_position) > ga + 1e-4
    assert m.attrs["mesh_efficiency"] < 1 - 0.05 * hv - 1e-3


def test_info_gives_no_impact_stiffness_for_a_flexible_mesh():
    """A mesh with a flexible gear has the compliant FE contact, not the IMPACT law's K: ``info``
    says so instead of a K it does not use; a rigid mesh keeps its K."""
    from flexgear.app.cli import info_text

    def used(preset):
        section = info_text(flexgear.load_config(preset)).split("## Pairs")[1].split("\n## ")[0]
        rows = [line for line in section.splitlines() if line.startswith("| ") and "a_w mm" not in line]
        return [row.split("|")[-2].strip() for row in rows]

    assert all(cell == "- (compliant FE contact)" for cell in used("spur_pair_flexible"))
    assert all(cell == "- (compliant FE contact)" for cell in used("mercury_1a_flexible"))
    assert all("N/m^" in cell for cell in used("spur_pair"))
