"""A root crack as a series compliance of the compliant contact law (issue 22): a crack of a RIGID
gear in a flexible set, and a crack over part of the face width of a flexible gear (whose FE body
stays healthy), enter the compliant law of the cracked tooth's contacts as ``h(F) + c_s F``, c_s
the FE pair's extra compliance of the cracked tooth (:func:`flexgear.stiffness.crack.crack_series_table`,
the FE source of the rigid law's factor), looked up per tooth, flank and contact radius
(:mod:`flexgear.dynamics.model.tooth_laws`, :func:`flexgear.dynamics.contact.teeth.contact_slices`).
A spall or chip over part of the face width enters it as slices in parallel with a common approach
(:func:`flexgear.dynamics.contact.laws.slice_approach`), as in the rigid law.

The set: the flexible spur pair with only the pinion flexible (FE level 0, 100 kHz cutoff, no
shafts, a 5 % mesh damping ratio), the pinion at 1 Hz (mesh period 42 ms against the wheel's
torsional mode near 8 kHz: quasi-static), the rigid wheel cracked on its loaded flank, 1.5 mm at
45 deg.

The law checked is the quasi-static load sharing of the FE statics, independent of the time
solver (:func:`~flexgear.stiffness.loaded_mesh.pair_compliance`, :func:`~flexgear.stiffness.loaded_mesh.share_load`
with the FE tooth tables of :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh` on its extended grid and the
crack's compliance from :func:`~flexgear.stiffness.crack.crack_pair_stiffness`): while the cracked
tooth shares the path with a neighbour, compatibility and equilibrium give it a smaller share, and
its passage's impulse drops by D. The model's statics (pinion FE + rigid wheel + the series
compliance) give D_model; the pair with both gears elastic and the crack a slit in the wheel's FE
gives D_fe < D_model (a rigid wheel makes the healthy pair stiffer, so the same extra compliance
takes a larger share). The run's drop lies within 5 % of D_model (measured 1.5-3.1 %: the flexible
pinion's reduced compliance against the statics' tooth tables, the run's ringing) and above D_fe.
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from flexgear.config import loads_config, preset_path
from flexgear.config.faults import loaded_flanks
from flexgear.dynamics.contact.laws import HEALTHY_TERMS, HERTZ_COLUMNS, HERTZ_SERIES
from flexgear.dynamics.contact.teeth import contact_slices, tooth_law
from flexgear.dynamics.flexible.reductions import reduction_jobs
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.model.tooth_laws import nominal_mesh_force
from flexgear.errors import ConfigError
from flexgear.fe.crack import root_crack
from flexgear.gears.geometry import GearPair
from flexgear.stiffness.compliance import DEFAULT_DEPTH, tooth_compliance, tooth_step
from flexgear.stiffness.crack import crack_pair_stiffness, cracked_gear_model
from flexgear.stiffness.hertz import hertz_approach
from flexgear.stiffness.loaded_mesh import loaded_mesh, pair_compliance, share_load

DEPTH = 1.5e-3  # m, at 45 deg
#: FE statics' mesh positions per base pitch (a spall band's ends fall between them: 48 puts the
#: half-width spall's drop 2.3 % below the run's, 24 5.5 %)
POSITIONS = 48
ANGLE = math.radians(45.0)
SPEED = 1.0  # Hz, pinion
Z_WHEEL = 21
RUN_IN = 5  # mesh periods (the load ramped in over the first 3)


def contact_series(meshes, m, ta, tb, sa, ra, rb) -> float:
    """The series compliance [m/N] :func:`contact_slices` puts into a contact's Hertz row (its
    arguments, the row's other per-tooth terms checked healthy where the flanks' whole width is)."""
    hp = np.full((1, HERTZ_COLUMNS), np.nan)
    contact_slices(meshes, m, ta, tb, sa, ra, rb, hp, 0)
    assert tuple(hp[0, HERTZ_SERIES + 1:]) == HEALTHY_TERMS[1:]  # cracks only: whole widths, no recess
    return float(hp[0, HERTZ_SERIES])


def _mesh_period() -> float:
    return 1.0 / (24 * SPEED)


def crack(tooth, gear="wheel", flank="left", width=1.0, depth=DEPTH):
    return (f'\n[[faults]]\nkind = "crack"\ngear = "{gear}"\ntooth = {tooth}\nflank = "{flank}"\n'
            f"depth = {depth!r}\nangle_deg = 45.0\nwidth_fraction = {width!r}\n")


def config(extra="", periods=4.0, gears=("pinion",)):
    """The set of the module docstring over ``periods`` mesh periods after the run-in."""
    text = preset_path("spur_pair_flexible").read_text()
    cfg = loads_config(text.replace("[simulation]", extra + "\n[simulation]"))
    cfg = cfg.use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible.update(level=0, cutoff=100e3, dynamic_cutoff=0.0, gears=list(gears))
    cfg.drive["speed_hz"] = SPEED
    T = _mesh_period()
    cfg.load["ramp"] = 3 * T
    cfg.simulation.update(step=2.5e-5, run_in=RUN_IN * T, duration=periods * T, antialias=False,
                          output_rate=10000.0)
    return cfg


def wheel_flank(cfg) -> tuple[int, str]:
    """(side, name) of the wheel's loaded flank."""
    side = loaded_flanks(cfg)["pinion-wheel"][1]
    return side, ("left" if side > 0 else "right")


def passages(cfg, res) -> dict:
    """{wheel tooth: (first sample, last sample, impulse [N s])} of every passage of a wheel
    tooth's loaded flank that starts and ends inside the record."""
    side, _ = wheel_flank(cfg)
    m = res.meshes["pinion-wheel"]
    loads = np.zeros((len(res.time), Z_WHEEL))
    hit = (m.pair_tooth_b >= 0) & (m.pair_side == side)  # external pair: the same flank side on both
    rows, cols = np.nonzero(hit)
    np.add.at(loads, (rows, m.pair_tooth_b[rows, cols]), m.pair_force[rows, cols])
    dt = res.time[1] - res.time[0]
    out = {}
    for k in range(Z_WHEEL):
        on = np.flatnonzero(loads[:, k] > 0)
        for part in np.split(on, np.flatnonzero(np.diff(on) > 1) + 1):
            if part.size and part[0] > 0 and part[-1] < len(res.time) - 1:
                out[k] = (part[0], part[-1], loads[part, k].sum() * dt)
    return out


def quasi_static_drops(cfg, cracks) -> dict:
    """{key: D_model} for each ``cracks`` entry key -> (gear, width_fraction), and "fe": D_fe of the
    wheel's through crack: the cracked tooth's loss of impulse over a passage, relative to a
    healthy tooth's, from the FE statics of the pair at the static mesh force (module docstring).
    At each position of the extended grid (contact beyond the path where the loaded tips touch,
    as the run's contact search finds it) the pairs share the load by compatibility with the FE
    tooth tables and nonlinear Hertz, as :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh`.
    D_model: the pinion's tables, the wheel rigid (Hertz to its near-field depth, as the
    flexible model's rigid gear), the cracked pair's extra compliance 1 / (w k_cracked +
    (1 - w) k_healthy) - 1 / k_healthy of the FE single-pair stiffnesses on the path (slices in
    parallel over the cracked width w; held beyond the path's ends, as the model's table).
    D_fe: both gears' tables, the crack a slit in the wheel's FE (its own compliance and its
    coupling to the neighbours)."""
    from test_flexible_ring_crack_run import crack_column

    job = reduction_jobs(cfg)[0]["pinion"]
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    pair = GearPair(g1, g2)
    F = nominal_mesh_force(cfg)
    mat, st, form = job["material"], job["settings"], job["formulation"]
    ms = loaded_mesh(pair, F, settings=st, material=mat, formulation=form, n_positions=POSITIONS, extended=True)
    tc1, tc2 = ms.c1, ms.c2
    slit, _ = cracked_gear_model(g2, root_crack(g2, DEPTH, ANGLE), st, mat, form)
    cracked = tooth_compliance(g2, tc2.radius, model=slit, material=mat, neighbours=tc2.reach)
    grid = ms.grid
    n, J = grid.n, len(grid.s)
    sig1, sig2 = tooth_step(g1), -tooth_step(g2)
    L = min(g1.face_width, g2.face_width)

    def slices(f, q, idx, d2, spall):
        """Approach [m] of a pair with a spall over part of the face width at its contact (the
        wheel's radius inside the spall's band): slices with a common approach a, the outline's
        part w of the width at the outline, the rest ``depth`` below it, each slice the
        whole-width Hertz law at its force per width (:func:`flexgear.gears.modified.partial_width_force`
        with the Hertz law)."""
        def hz(P):
            return hertz_approach(P, grid.R[idx[q]], L, mat, mat, tc1.depth, d2, "plane_strain")

        def inverse(x):
            return brentq(lambda P: hz(P) - x, 1e-9, 1e6, xtol=1e-12, rtol=1e-14) if x > hz(1e-9) else 0.0

        w = 1.0 - spall.width_fraction
        top = hz(f / w)  # the outline slice alone
        if top <= spall.depth:
            return top
        return brentq(lambda a: w * inverse(a) + (1.0 - w) * inverse(a - spall.depth) - float(f), 0.0, top,
                      xtol=1e-16, rtol=1e-14)

    def impulse(kind, series=None, spall=None):
        """Impulse of a tooth's passage over the grid [N m] (kind: healthy, fe, rigid)."""
        load = np.zeros(J)
        for j in range(J):
            idx = list(range(j % n, J, n))
            i = idx.index(j)
            if kind == "rigid":
                C = np.array([[tc1.bulk[idx[a]] if a == b else tc1.coupling[sig1 * (a - b)][idx[a], idx[b]]
                               for b in range(len(idx))] for a in range(len(idx))])
                d2 = DEFAULT_DEPTH * g2.module  # the flexible model's rigid gear
                if series is not None:
                    C[i, i] += series[j]
            else:
                C = pair_compliance(tc1, tc2, idx, sig1, sig2)
                d2 = tc2.depth
                if kind == "fe":
                    crack_column(C, idx, i, tc1, tc2, cracked, sig2)

            def hertz(q, f, idx=idx, d2=d2, j=j):
                if spall is not None and idx[q] == j and min(spall.start_radius, spall.end_radius) < \
                        tc2.radius[j] < max(spall.start_radius, spall.end_radius):
                    return slices(f, q, idx, d2, spall)
                return hertz_approach(f, grid.R[idx[q]], L, mat, mat, tc1.depth, d2, "plane_strain")

            Fk, _ = share_load(C, hertz, F, gap=grid.gap[idx], arm=grid.arm[idx])
            load[j] = Fk[i]
        return np.trapezoid(load, grid.s)

    out = {"fe": 1.0 - impulse("fe") / impulse("healthy")}
    rigid = impulse("rigid")
    fes = {}
    for key, (gear, w) in cracks.items():
        if gear == "spall":  # w: the wheel's Spall
            out[key] = 1.0 - impulse("rigid", spall=w) / rigid
            continue
        which = 1 if gear == "pinion" else 2
        g, tc = (g1, tc1) if which == 1 else (g2, tc2)
        if which not in fes:  # one FE per cracked gear (the width enters below), one healthy pair
            healthy = next(iter(fes.values())).healthy if fes else None
            fes[which] = crack_pair_stiffness(pair, DEPTH, ANGLE, F, cracked=which, settings=st, material=mat,
                                              formulation=form, n_positions=POSITIONS, healthy=healthy)
        fe = fes[which]
        on = fe.on_path
        kp = w * fe.k_cracked[on] + (1.0 - w) * fe.k_healthy[on]
        r_on = g.rb * np.sqrt(1.0 + fe.roll[on] ** 2)
        order = np.argsort(r_on)
        series = np.interp(tc.radius, r_on[order], (1.0 / kp - 1.0 / fe.k_healthy[on])[order])
        out[key] = 1.0 - impulse("rigid", series) / rigid
    return out


# ------------------------------------------------------------------------------------------------
# the per-tooth table
# ------------------------------------------------------------------------------------------------
def test_the_series_compliance_sits_on_the_cracked_flank_only_and_is_the_fe_pairs():
    """The rigid wheel's crack in a mesh with the flexible pinion: the table row of the wheel's
    tooth 3, loaded flank, holds c_s = 1 / k_cracked - 1 / k_healthy of the FE pair (the cracked
    tooth's extra bulk compliance delta_c; 1 % at the table's interpolation), law factor 1;
    every other tooth, flank and the pinion read exactly 0.0 (and the IMPACT law's 1, 1, 0). Half
    the width: 1 / (k_c / 2 + k_h / 2) - 1 / k_h, between 0 and the through crack's. A zero-size
    crack builds no table. Catches: the crack on the wrong tooth, flank or gear side; a factor
    instead of a compliance; a table for a healthy tooth."""
    cfg = config(crack(3) + crack(9, width=0.5))
    side, _ = wheel_flank(cfg)
    model = build_model(cfg)
    meshes = model.pack().meshes
    pair = GearPair(cfg.gears["pinion"], cfg.gears["wheel"])
    job = reduction_jobs(cfg)[0]["pinion"]
    cps = crack_pair_stiffness(pair, DEPTH, ANGLE, nominal_mesh_force(cfg), cracked=2, settings=job["settings"],
                               material=job["material"], formulation=job["formulation"])
    on = cps.on_path
    r = cfg.gears["wheel"].rb * np.sqrt(1.0 + cps.roll[on] ** 2)
    full, half = cps.delta_c[on], 1.0 / (0.5 * cps.k_cracked[on] + 0.5 * cps.k_healthy[on]) - 1.0 / cps.k_healthy[on]

    def series(tb, sb, g=1):
        # contact_series(meshes, m, ta, tb, sa, ra, rb): the wheel is gear B of the external mesh 0
        return np.array([contact_series(meshes, 0, tb if g == 0 else 0, tb, sb, x, x) for x in r])

    assert np.allclose(series(3, side), full, rtol=1e-2) and full.min() > 0.0
    assert np.allclose(series(9, side), half, rtol=1e-2) and np.all((half > 0) & (half < full))
    # in series with the FE pair, the half crack's pair stiffness is the slices in parallel; the
    # rigid law's factor for the same crack (kappa = rho^e / 2 + 1/2) gives kappa^(1/e), larger by
    # Jensen's second-order term (e - 1) w (1 - w) (1 - rho)^2 / 2 (theory page *Root crack*)
    rho, e = cps.ratio[on], cfg.contact_law(pair).e
    flexible = 1.0 / (1.0 + series(9, side) * cps.k_healthy[on])
    assert np.allclose(flexible, 0.5 * rho + 0.5, rtol=1e-3)
    gap = (0.5 * rho**e + 0.5) ** (1.0 / e) - flexible
    assert np.all((gap > 0.0) & (gap < 1.2 * (e - 1.0) * 0.25 * (1.0 - rho) ** 2 / 2 + 1e-3))
    for tb, sb in ((3, -side), (4, side), (2, side), (9, -side), (10, side)):
        assert np.all(series(tb, sb) == 0.0), (tb, sb)
    assert np.all([contact_series(meshes, 0, 3, 0, side, x, x) == 0.0 for x in r])
    assert np.all([tooth_law(meshes.teeth, 0, 1, 3, side, x) == (1.0, 1.0, 0.0) for x in r])
    assert build_model(config(crack(3, depth=0.0) + crack(9, width=0.0))).tooth_laws is None


# ------------------------------------------------------------------------------------------------
# runs
# ------------------------------------------------------------------------------------------------
PERIODS = 10  # mesh periods recorded: seven wheel-tooth passages whole in the record (faults two apart)


def _run(cfg):
    from flexgear.app.run import run

    return run(cfg)


def order(res, column: str) -> list:
    """Teeth of the pinion (``pair_tooth_a``) or the wheel (``pair_tooth_b``) seen in the record,
    in the order they first touch."""
    first = {}
    for i, row in enumerate(getattr(res.meshes["pinion-wheel"], column)):
        for t in row[row >= 0]:
            first.setdefault(int(t), i)
    return sorted(first, key=first.get)


def whole(cfg, res) -> list:
    """Wheel teeth with a whole passage in the record, in the order they pass."""
    return [k for k, _ in sorted(passages(cfg, res).items(), key=lambda kv: kv[1][0])]


@pytest.fixture(scope="module")
def healthy():
    cfg = config(periods=PERIODS)
    return cfg, _run(cfg)


@pytest.fixture(scope="module")
def cracked(healthy):
    """(cracks, cfg, result): the wheel's first whole passage in the record cracked through the
    face width (key "wheel"), the one two pitches later over half the width ("wheel/2"), and the
    flexible pinion's tooth that meets the wheel tooth two pitches after that, over half the width
    ("pinion/2": healthy FE body plus the series compliance)."""
    cfg, res = healthy
    wheel = whole(cfg, res)
    k0, k2, k4 = wheel[0], wheel[2], wheel[4]
    m = res.meshes["pinion-wheel"]
    side, flank = wheel_flank(cfg)
    i0, i1, _ = passages(cfg, res)[k4]
    mid = (i0 + i1) // 2
    hit = (m.pair_tooth_b[mid] == k4) & (m.pair_side[mid] == side)
    p4 = int(m.pair_tooth_a[mid][hit][0])
    blocks = crack(k0, flank=flank) + crack(k2, flank=flank, width=0.5) + crack(p4, gear="pinion", flank=flank,
                                                                                  width=0.5)
    cfg_c = config(blocks + spall(wheel[6], flank), periods=PERIODS)
    return {"wheel": k0, "wheel/2": k2, "pinion/2": (p4, k4), "spall/2": wheel[6]}, cfg_c, _run(cfg_c)


#: The half-width spall: on the wheel's flank near its root (the end of its passage, shared with
#: the next tooth)
SPALL_ROLL_DEG = (9.0, 17.0)
SPALL_DEPTH = 5.0e-6  # m: below the outline slice's Hertz approach at the mesh force, the recessed slice carries


def spall(tooth, flank="left", width=0.5):
    return (f'\n[[faults]]\nkind = "spall"\ngear = "wheel"\ntooth = {tooth}\nflank = "{flank}"\n'
            f"start_roll_deg = {SPALL_ROLL_DEG[0]!r}\nend_roll_deg = {SPALL_ROLL_DEG[1]!r}\n"
            f"depth = {SPALL_DEPTH!r}\nwidth_fraction = {width!r}\n")


@pytest.fixture(scope="module")
def drops(healthy):
    cfg = config(spall(0, wheel_flank(healthy[0])[1]))
    return quasi_static_drops(healthy[0], {"wheel": ("wheel", 1.0), "wheel/2": ("wheel", 0.5),
                                           "pinion/2": ("pinion", 0.5), "spall/2": ("spall", cfg.faults[0])})


def test_a_crack_out_of_mesh_and_zero_size_faults_give_the_healthy_run_bit_for_bit(healthy):
    """A crack of the rigid wheel and a half-width crack of the flexible pinion, each on a tooth
    that stays out of mesh over the run (their table rows are looked up at every contact of the
    mesh: the healthy teeth's series compliance 0.0 adds exactly nothing), and zero-size cracks
    (depth 0, width 0: no table) give the healthy flexible run bit for bit."""
    cfg, ref = healthy
    z1 = cfg.gears["pinion"].z
    # the run-in meshes the few teeth before the record's first ones (five mesh periods): take
    # teeth three after the last ones the record sees
    idle = []
    for column, z in (("pair_tooth_b", Z_WHEEL), ("pair_tooth_a", z1)):
        seen = order(ref, column)
        step = 1 if (seen[-1] - seen[-2]) % z == 1 else -1
        idle.append((seen[-1] + 3 * step) % z)
    idle_w, idle_p = idle
    _, flank = wheel_flank(cfg)
    extra = (crack(idle_w, flank=flank) + crack(idle_p, gear="pinion", flank=flank, width=0.5)
             + crack((idle_w + 1) % Z_WHEEL, flank=flank, depth=0.0) + crack(5, gear="pinion", flank=flank, width=0.0))
    got = _run(config(extra, periods=PERIODS))
    model = build_model(config(extra, periods=PERIODS))
    assert (model.tooth_laws.first[0] >= 0).all()  # both gears' rows are live
    a, b = ref.meshes["pinion-wheel"], got.meshes["pinion-wheel"]
    for name in ("normal_force", "pair_force", "pair_tooth_a", "pair_tooth_b", "penetration", "pair_deflection"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for body in ("pinion", "wheel"):
        assert np.array_equal(ref.bodies[body].angle, got.bodies[body].angle)
        assert np.array_equal(ref.bodies[body].angular_velocity, got.bodies[body].angular_velocity)


def test_a_cracked_tooth_carries_less_over_its_passage_as_the_fe_statics_say(healthy, cracked, drops):
    """The run's drop D of each cracked tooth's passage impulse against the mean healthy passage:

    * the rigid wheel's through crack and half-width crack, the flexible pinion's half-width
      crack and the rigid wheel's half-width spall (slices of the compliant law), within 5 % of
      D_model of the FE statics (measured -0.06, -0.13, -1.4, +2.4 %);
    * the through crack of the rigid wheel above D_fe, the drop of the same crack as a slit in an
      elastic wheel's FE (the rigid wheel's pair is stiffer, the crack's share of its compliance
      larger);
    * the half-width crack's drop between 0 and the through crack's, at the ratio of the statics
      (slices in parallel: about one half), 5 %.

    The change is there only while the cracked tooth is in mesh: at every sample where no cracked
    tooth carries load, every pair's load equals the healthy run's within 1 % of the mesh force.
    Catches: no series term (D = 0), one on the wrong tooth, flank or gear (the wrong passage drops,
    or the samples away from the crack change), a compliance of the wrong size (the bounds), a
    factor of the rigid law in its place (the compliant law reads none: D = 0), a spall's slices
    missing or with the wrong recess or width (its bound)."""
    cfg, ref = healthy
    keys, cfg_c, res = cracked
    h, c = passages(cfg, ref), passages(cfg_c, res)
    sound = np.mean([v[2] for v in h.values()])
    assert np.ptp([v[2] for v in h.values()]) < 2e-3 * sound  # quasi-static: the healthy passages alike
    got = {key: 1.0 - c[keys[key]][2] / sound for key in ("wheel", "wheel/2")}
    # the pinion tooth's passage: its loaded-flank pair with the wheel tooth it meets
    p4, k4 = keys["pinion/2"]
    got["pinion/2"] = 1.0 - c[k4][2] / sound
    got["spall/2"] = 1.0 - c[keys["spall/2"]][2] / sound
    for key, d in got.items():
        assert abs(d / drops[key] - 1.0) < 0.05, (key, d, drops[key])
    assert drops["fe"] < got["wheel"]
    assert 0.0 < got["wheel/2"] < got["wheel"]
    assert got["wheel/2"] / got["wheel"] == pytest.approx(drops["wheel/2"] / drops["wheel"], rel=0.05)
    # only while a cracked tooth is in mesh
    a, b = ref.meshes["pinion-wheel"], res.meshes["pinion-wheel"]
    live = ((np.isin(b.pair_tooth_b, [keys["wheel"], keys["wheel/2"], keys["spall/2"]]) | (b.pair_tooth_a == p4))
            & (b.pair_force > 0)).any(axis=1)
    away = ~live
    away[: np.argmax(live)] = False  # from the first cracked engagement on (before it: bit for bit)
    assert away.sum() > 200
    F = nominal_mesh_force(cfg)
    for i in np.flatnonzero(away):
        la = {(ta, tb): f for ta, tb, f in zip(a.pair_tooth_a[i], a.pair_tooth_b[i], a.pair_force[i]) if ta >= 0}
        lb = {(ta, tb): f for ta, tb, f in zip(b.pair_tooth_a[i], b.pair_tooth_b[i], b.pair_force[i]) if ta >= 0}
        for pair_ in set(la) | set(lb):
            assert abs(la.get(pair_, 0.0) - lb.get(pair_, 0.0)) < 0.01 * F, (i, pair_)


def chip(tooth, flank, width):
    return (f'\n[[faults]]\nkind = "chip"\ngear = "pinion"\ntooth = {tooth}\nflank = "{flank}"\n'
            f"profile_size = 0.6e-3\ntip_size = 0.3e-3\nwidth_fraction = {width!r}\n")


def test_a_partial_chip_of_the_flexible_pinion_sheds_load_to_the_next_pair_and_less_than_a_through_chip(healthy):
    """A tip chip (0.6 mm down the profile, 0.3 mm along the tip) of the flexible pinion's tooth that
    meets a wheel tooth mid-record, over half the face width (the healthy FE body plus the slices
    of the compliant law: the chipped half recessed) and through the width (meshed into the FE
    body, its own reduction), in the quasi-static run: the passage of the chipped pair carries
    less impulse (measured 1.2 % and 4.5 %; the healthy passages agree within 0.11 %), the half
    chip less than the through one (the intact half still carries on the chipped band); the
    impulse goes to the neighbouring pair, whose passage gains about as much, and the mesh's total
    stays (the load is the same: sum of the changes within 0.1 % of a passage; the other
    passages within 0.3 %). Catches a partial chip's slices missing (no drop), on another tooth
    or flank (another passage drops, or none), or a recess that adds load (a gain)."""
    cfg, ref = healthy
    side, flank = wheel_flank(cfg)
    wheel = whole(cfg, ref)
    k = wheel[3]
    i0, i1, _ = passages(cfg, ref)[k]
    m = ref.meshes["pinion-wheel"]
    mid = (i0 + i1) // 2
    hit = (m.pair_tooth_b[mid] == k) & (m.pair_side[mid] == side)
    tooth = int(m.pair_tooth_a[mid][hit][0])
    h = passages(cfg, ref)
    sound = np.mean([v[2] for v in h.values()])
    assert np.ptp([v[2] for v in h.values()]) < 2e-3 * sound
    drops = {}
    for width in (0.5, 1.0):
        c_cfg = config(chip(tooth, flank, width), periods=PERIODS)
        c = passages(c_cfg, _run(c_cfg))
        assert set(c) == set(h)
        d = {w: 1.0 - c[w][2] / sound for w in c}
        others = sorted(d[w] for w in d if w != k)
        assert d[k] > 5e-3, (width, d)
        assert -others[0] > 0.8 * d[k] and max(abs(x) for x in others[1:]) < 3e-3, (width, d)
        assert abs(sum(d.values())) < 1e-3, (width, d)
        drops[width] = d[k]
    assert drops[0.5] < drops[1.0]


def test_the_deformed_view_reconstructs_the_cracked_pairs_force_with_the_series_compliance(cracked, tmp_path):
    """The deformed view's elastic force of each pair (penetration less deflection = h(F) + c_s F,
    or the spall's slices, solved for F) equals the recorded pair force over the through-cracked
    and the spalled tooth's passages (1e-4: the damper's part, quasi-static). Without c_s the
    cracked pair's would be off by a factor of about 2.8 (measured)."""
    from flexgear.results.deformed import DeformedGears
    from flexgear.results.store import save

    keys, cfg, res = cracked
    save(res, tmp_path / "results.h5")
    view = DeformedGears(tmp_path / "results.h5", stresses=False)
    m = res.meshes["pinion-wheel"]
    for key in ("wheel", "spall/2"):
        i0, i1, _ = passages(cfg, res)[keys[key]]
        seen = 0
        for i in np.linspace(i0 + 5, i1 - 5, 8).astype(int):
            loads, unmatched = view.contact_loads(int(i))
            assert not unmatched
            for fl in (f for body in loads.values() for f in body):
                assert fl.force == pytest.approx(m.pair_force[i, fl.slot], rel=1e-4), (key, i)
                seen += m.pair_tooth_b[i, fl.slot] == keys[key]
        assert seen >= 8


# ------------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------------
def test_every_fault_of_a_flexible_set_is_read_and_a_width_fraction_out_of_range_is_named():
    """Cracks, spalls and chips of a flexible set over any part of the face width are read (their
    runs: the tests above); a face-width fraction outside [0, 1] is refused when the file is read,
    naming the fault, the key, the value and the rule."""
    chip = ('\n[[faults]]\nkind = "chip"\ngear = "pinion"\ntooth = 7\nflank = "left"\nprofile_size = 0.5e-3\n'
            'tip_size = 0.2e-3\nwidth_fraction = 0.25\n')
    cfg = config(crack(3) + crack(4, width=0.5) + crack(5, gear="pinion", width=0.5) + spall(9) + chip)
    assert [f.width_fraction for f in cfg.faults] == [1.0, 0.5, 0.5, 0.5, 0.25]
    with pytest.raises(ConfigError, match=r"faults\[0\].*width_fraction.*1\.5.*\[0, 1\]"):
        config(crack(3, width=1.5))


# ------------------------------------------------------------------------------------------------
# which law takes a crack: per mesh, in a planetary set
# ------------------------------------------------------------------------------------------------
def _planetary(extra, flexible):
    """MERCURY 1-A flexible with ``flexible`` gears, FE level 0, and the rigid model of the same set
    (the tables need the meshes only: no reduction)."""
    cfg = loads_config(preset_path("mercury_1a_flexible").read_text().replace("[simulation]", extra + "\n[simulation]"))
    cfg.flexible.update(level=0, gears=list(flexible))
    cfg.fe["level"] = 0
    rigid = loads_config(preset_path("mercury_1a_flexible").read_text().replace("[simulation]", extra + "\n[simulation]"))
    rigid.flexible = None
    return cfg, build_model(rigid)


@pytest.mark.slow
def test_a_rigid_ring_crack_sits_on_the_ring_side_of_every_planet_ring_mesh_and_a_rigid_sun_crack_keeps_the_factor():
    """MERCURY 1-A, sun and planets flexible, the ring rigid with tooth 0 cracked on its left flank:
    each planet-ring mesh (the ring is gear B, internal) holds the series compliance on the ring's
    side, read through the planet's flank -sa of an internal mesh, equal to c_s of the planet-ring
    pair with the ring cracked (1 %), 0.0 on the ring's other flank and teeth and on the planet
    side; the sun-planet meshes have no rows. With only the ring flexible, a crack of the rigid sun
    sits in the sun-planet meshes, rigid ones: the IMPACT law's factor (< 1), series 0.0. Catches:
    the internal flank's sign, a compliance in a rigid mesh or a factor in a compliant one.
    Slow: 23 s of CPU with the FE tables cached (the MERCURY contact tables and crack lookups)."""
    from flexgear.dynamics.model.tooth_laws import tooth_law_table
    from flexgear.stiffness.crack import crack_series_table

    cfg, model = _planetary('\n[[faults]]\nkind = "crack"\ngear = "ring"\ntooth = 0\nflank = "left"\n'
                            'depth = 1.0e-3\nangle_deg = 45.0\n', ("sun", "planet"))
    model.tooth_laws = tooth_law_table(cfg, model)
    meshes = model.pack().meshes
    ring = cfg.gears["ring"]
    pair = GearPair(cfg.gears["planet"], ring)
    job = reduction_jobs(cfg)[0]["planet"]
    roll, c_s = crack_series_table(pair, 1.0e-3, ANGLE, nominal_mesh_force(cfg), cracked=2, settings=job["settings"],
                                   formulation=job["formulation"], material=job["material"])
    r = ring.rb * np.sqrt(1.0 + roll**2)
    names = [m.name for m in model.meshes]
    for m, name in enumerate(names):
        first = model.tooth_laws.first[m]
        if "ring" not in name:
            assert (first < 0).all(), name
            continue
        assert first[0] < 0 <= first[1], name
        # the ring's left flank (+1) meets the planet's flank sa = -1 of the internal mesh
        got = np.array([contact_series(meshes, m, 5, 0, -1, 0.0, x) for x in r])
        assert np.allclose(got, c_s, rtol=1e-2) and c_s.min() > 0.0, name
        for tb, sa in ((0, 1), (1, -1), (65, -1)):
            assert all(contact_series(meshes, m, 5, tb, sa, 0.0, x) == 0.0 for x in r), (name, tb, sa)
        assert all(tooth_law(meshes.teeth, m, 1, 0, 1, x) == (1.0, 1.0, 0.0) for x in r)

    cfg, model = _planetary('\n[[faults]]\nkind = "crack"\ngear = "sun"\ntooth = 2\nflank = "left"\n'
                            'depth = 1.0e-3\nangle_deg = 45.0\n', ("ring",))
    model.tooth_laws = tooth_law_table(cfg, model)
    meshes = model.pack().meshes
    sun = cfg.gears["sun"]
    x = np.linspace(sun.rb * 1.02, sun.ra * 0.98, 9)
    for m, name in enumerate(m.name for m in model.meshes):
        if not name.startswith("sun"):
            assert (model.tooth_laws.first[m] < 0).all(), name
            continue
        kappa = np.array([tooth_law(meshes.teeth, m, 0, 2, 1, v)[0] for v in x])
        assert np.all(kappa < 1.0) and all(contact_series(meshes, m, 2, 0, 1, v, 0.0) == 0.0 for v in x), name


# ------------------------------------------------------------------------------------------------
# a rigid ring's crack in a flexible planetary set
# ------------------------------------------------------------------------------------------------
def ring_drops(cfg) -> tuple[float, float]:
    """(D_mesh, D_path) of tests/test_flexible_ring_crack_run.py for the RIGID cracked ring: the
    planet's FE tooth tables, the ring rigid (Hertz to its near-field depth) and the cracked pair's
    extra compliance delta_c of :func:`~flexgear.stiffness.crack.crack_pair_stiffness` (the planet-ring
    pair, the ring cracked) in series; D_path with the planet's share 3 r / (r + 2) of a planet
    whose path were its ring mesh alone."""
    from test_flexible_ring_crack import ANGLE as RING_ANGLE
    from test_flexible_ring_crack import DEPTH as RING_DEPTH

    job = reduction_jobs(cfg)[0]["planet"]
    pair = GearPair(cfg.gears["planet"], cfg.gears["ring"])
    F = nominal_mesh_force(cfg)
    cps = crack_pair_stiffness(pair, RING_DEPTH, RING_ANGLE, F, cracked=2, settings=job["settings"],
                               material=job["material"], formulation=job["formulation"], n_positions=12)
    tc1, grid = cps.healthy.c1, cps.healthy.grid
    n, J = grid.n, len(grid.s)
    sig1 = tooth_step(pair.g1)
    L = min(pair.g1.face_width, pair.g2.face_width)
    mat, d2 = job["material"], DEFAULT_DEPTH * pair.g2.module

    def tooth(crack):
        load, te = np.zeros(J), np.zeros(J)
        for j in range(J):
            idx = list(range(j % n, J, n))
            i = idx.index(j)
            C = np.array([[tc1.bulk[idx[a]] if a == b else tc1.coupling[sig1 * (a - b)][idx[a], idx[b]]
                           for b in range(len(idx))] for a in range(len(idx))])
            if crack:
                C[i, i] += cps.delta_c[j]

            def hertz(q, f, idx=idx):
                return hertz_approach(f, grid.R[idx[q]], L, mat, mat, tc1.depth, d2, "plane_strain")

            Fk, te[j] = share_load(C, hertz, F, gap=grid.gap[idx], arm=grid.arm[idx])
            load[j] = Fk[i]
        return load, te

    from test_flexible_ring_crack_run import drop_bounds

    return drop_bounds(tooth, grid.s)


def _ring_run(cracked: bool, periods: float):
    """tests/test_flexible_ring_crack_run.py's run with the ring rigid (sun and planets flexible)."""
    import test_flexible_ring_crack_run as R

    text = preset_path("mercury_1a_flexible").read_text()
    cfg = loads_config(text.replace("[simulation]", (R.FAULT if cracked else "") + "\n[simulation]"))
    cfg = cfg.use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible.update(level=0, cutoff=100e3, dynamic_cutoff=0.0, gears=["sun", "planet"])
    cfg.drive["speed_hz"] = R.SPEED
    T = R._mesh_period(cfg)
    cfg.load["ramp"] = 5 * T
    cfg.simulation.update(step=2.5e-5, run_in=R.RUN_IN * T, duration=periods * T, antialias=False,
                          output_rate=10000.0)
    return cfg, _run(cfg)


@pytest.mark.slow
def test_a_cracked_rigid_ring_tooth_carries_less_over_a_planets_passage():
    """MERCURY 1-A with the sun and the planets flexible and the ring rigid, ring tooth 0 cracked
    (1 mm at 45 deg, left flank: the crack of tests/test_flexible_ring_crack_run.py), 24 mesh
    periods after the run-in: planet 2's passage of the cracked tooth loses D = 4.6 %, between
    D_mesh = 3.3 % and D_path = 6.3 % of the FE statics with the rigid ring (:func:`ring_drops`;
    the flexible ring's slit: 3.1 % between 2.1 and 3.9 %), and the checks of that test (the
    neighbours and the other planets gain, the passages away from the crack within 2 %). Catches
    the internal mesh's flank or radius mapping of the series compliance (the drop on the wrong
    tooth or none). Slow: 20 s of CPU with the reductions cached."""
    import test_flexible_ring_crack_run as R

    (cfg, healthy), (_, cracked) = _ring_run(False, 24), _ring_run(True, 24)
    R._check(R.passages(cfg, healthy), R.passages(cfg, cracked), ring_drops(cfg), (2,))
