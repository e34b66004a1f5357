"""A root crack in the flexible ring in a time-domain run (issue 22): MERCURY 1-A with the sun, the
planets and the ring flexible (FE level 0, 100 kHz cutoff, no shafts, a 5 % mesh damping ratio),
ring tooth 0 cracked at the root of its loaded (left) flank, 1 mm (half the module) at 45 deg, as
a slit in the ring's FE body: the crack and the reduction of tests/test_flexible_ring_crack.py,
whose module fixture reduces it into the session's cache, where this run finds it. The sun turns
at 2 Hz (mesh period 28 ms: quasi-static).

The law checked is the quasi-static load sharing of the FE statics, independent of the time
solver (:func:`flexgear.stiffness.crack.crack_pair_stiffness`: the planet-ring pair's tooth
compliance tables, healthy and with the ring cracked, the same crack and mesh level): while the
cracked tooth shares the path with a neighbour (contact ratio 1.73), compatibility and
equilibrium of the two pairs give it a smaller share than a healthy tooth, and its passage's
impulse drops by D_mesh. That holds if the planet's load stays what it was; but the three
planets are springs in parallel between the driven sun and the carrier, so a planet whose ring
mesh softens also sheds part of its load to the other two. If that planet's path were its ring
mesh alone (sun mesh and planet rigid), its share at each position would be 3 r / (r + 2) with r
the ring mesh's stiffness over the healthy one there (the transmission errors' ratio; the planets
mesh in phase, z_s / 3 and z_r / 3 being whole), and the drop D_path > D_mesh. The run's drop lies
between: D_mesh < D < D_path.
"""
import numpy as np
import pytest
from test_flexible_ring_crack import ANGLE, DEPTH, TOOTH

from flexgear.config import load_config, loads_config, preset_path
from flexgear.dynamics.flexible.reductions import reduction_jobs
from flexgear.dynamics.model.tooth_laws import nominal_mesh_force
from flexgear.gears.faults import LEFT
from flexgear.gears.geometry import GearPair
from flexgear.stiffness.compliance import tooth_step
from flexgear.stiffness.crack import crack_pair_stiffness
from flexgear.stiffness.hertz import hertz_approach
from flexgear.stiffness.loaded_mesh import pair_compliance, share_load

#: Planets 1, 2, 3 start at ring teeth 16, 38, 60 (tests/test_rigid_crack.py) and meet tooth 0
#: (66) in the order 3, 2, 1, each 22 mesh periods after the one before: planet 3 within the
#: run-in, then planet 2 about 19 periods after the run-in, planet 1 after 41, planet 3 after 63.
SPEED = 2.0  # Hz, sun
Z_RING = 66
RUN_IN = 8  # mesh periods (the load ramped in over the first 5)
FAULT = (f'\n[[faults]]\nkind = "crack"\ngear = "ring"\ntooth = {TOOTH}\nflank = "left"\ndepth = {DEPTH}\n'
         'angle_deg = 45.0\n')


def _mesh_period(cfg) -> float:
    s, r = cfg.gears["sun"], cfg.gears["ring"]
    return 1.0 / (r.z * cfg.drive["speed_hz"] * s.z / (s.z + r.z))


def _run(cracked: bool, periods: float):
    """(cfg, result) of the set above over ``periods`` mesh periods after the run-in."""
    from flexgear.app.run import run

    text = preset_path("mercury_1a_flexible").read_text()
    cfg = loads_config(text.replace("[simulation]", (FAULT if cracked else "") + "\n[simulation]"))
    cfg = cfg.use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible.update(level=0, cutoff=100e3, dynamic_cutoff=0.0)
    cfg.drive["speed_hz"] = SPEED
    T = _mesh_period(cfg)
    cfg.load["ramp"] = 5 * T
    cfg.simulation.update(step=2.5e-5, run_in=RUN_IN * T, duration=periods * T, antialias=False,
                          output_rate=10000.0)
    return cfg, run(cfg)


def passages(cfg, res) -> dict:
    """{(planet, ring tooth): (first sample, last sample, impulse [N s])} of every passage of a
    ring tooth's loaded (left) flank along a planet that starts and ends inside the record."""
    z = cfg.gears["ring"].z
    dt = res.time[1] - res.time[0]
    out = {}
    for p in range(1, cfg.planetary["planets"] + 1):
        m = res.meshes[f"planet{p}-ring"]
        loads = np.zeros((len(res.time), z))
        hit = (m.pair_tooth_b >= 0) & (m.pair_side == -LEFT)  # the planet's side of the ring's left flank
        rows, cols = np.nonzero(hit)
        np.add.at(loads, (rows, m.pair_tooth_b[rows, cols]), m.pair_force[rows, cols])
        for k in range(z):
            on = np.flatnonzero(loads[:, k] > 0)
            for part in np.split(on, np.flatnonzero(np.diff(on) > 1) + 1):
                if part.size and part[0] > 0 and part[-1] < len(res.time) - 1:
                    out[p, k] = (part[0], part[-1], loads[part, k].sum() * dt)
    return out


def quasi_static_drops(cfg) -> tuple[float, float]:
    """(D_mesh, D_path): the cracked ring tooth's loss of impulse over a passage, relative to a
    healthy tooth's, from the FE statics of the planet-ring pair at the static mesh force (module
    docstring). The pairs on the path at each grid position share the load by compatibility with
    the FE tables (the cracked tooth's own compliance and its coupling to the neighbours from the
    cracked ring) and nonlinear Hertz, as :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh`."""
    cfg = load_config("mercury_1a_flexible") if cfg is None else cfg
    job = reduction_jobs(cfg)[0]["ring"]
    pair = GearPair(cfg.gears["planet"], cfg.gears["ring"])
    F = nominal_mesh_force(cfg)
    cps = crack_pair_stiffness(pair, DEPTH, ANGLE, F, cracked=2, settings=job["settings"], material=job["material"],
                               formulation=job["formulation"], n_positions=12)
    ms = cps.healthy
    tc1, tc2, cracked = ms.c1, ms.c2, cps.cracked_mesh.c2
    grid = ms.grid
    n, J = grid.n, len(grid.s)
    sig1, sig2 = tooth_step(pair.g1), -tooth_step(pair.g2)
    L = min(pair.g1.face_width, pair.g2.face_width)
    mat = job["material"]

    def tooth(crack):
        """Load [N] of the tooth at grid point j and the transmission error there [m], each j."""
        load, te = np.zeros(J), np.zeros(J)
        for j in range(J):
            idx = list(range(j % n, J, n))
            i = idx.index(j)
            C = pair_compliance(tc1, tc2, idx, sig1, sig2)
            if crack:
                crack_column(C, idx, i, tc1, tc2, cracked, sig2)

            def hertz(q, f):
                return hertz_approach(f, grid.R[idx[q]], L, mat, mat, tc1.depth, tc2.depth, "plane_strain")

            Fk, te[j] = share_load(C, hertz, F, gap=grid.gap[idx], arm=grid.arm[idx])
            load[j] = Fk[i]
        return load, te

    return drop_bounds(tooth, grid.s)


def crack_column(C, idx, i, tc1, tc2, cracked, sig2) -> None:
    """Put gear 2's cracked tooth into the pair compliance ``C`` (:func:`pair_compliance` of
    the contacts at grid indices ``idx``) in place: contact i, on the cracked tooth, takes its
    bulk compliance from ``cracked`` (gear 2's compliance tables with the crack), and so do its
    couplings to the other contacts (C symmetric by reciprocity)."""
    j = idx[i]
    C[i, i] = tc1.bulk[j] + cracked.bulk[j]
    for a in range(len(idx)):
        if a != i:
            d = sig2 * (a - i)
            C[a, i] += cracked.coupling[d][idx[a], j] - tc2.coupling[d][idx[a], j]
            C[i, a] = C[a, i]


def drop_bounds(tooth, s) -> tuple[float, float]:
    """(D_mesh, D_path) from ``tooth(cracked)`` -> (the tooth's load, the transmission error) along
    the path coordinates ``s``: the loss of the cracked tooth's impulse with the planet's load
    unchanged, and with the planet's share 3 r / (r + 2) of a planet whose path were its ring mesh
    alone (r: healthy over cracked transmission error; the three planets in parallel)."""
    (h, te_h), (c, te_c) = tooth(False), tooth(True)
    r = te_h / te_c
    healthy = np.trapezoid(h, s)
    return 1.0 - np.trapezoid(c, s) / healthy, 1.0 - np.trapezoid(c * 3 * r / (r + 2), s) / healthy


def _check(healthy, cracked, drops, planets):
    """The run's passages against the law (module docstring) at the passages of the cracked tooth
    by ``planets``: D_mesh < D < D_path, where D is its impulse's loss against the mean healthy
    passage. The passages that share the time of one (its two neighbours along that planet, the
    teeth then in mesh with the other planets) take the difference: the tooth passing before it
    shares its ring-tip end, where the crack softens it most (the static test: the drop grows
    towards the ring's tip), and gains more than any passage away from the crack deviates; the
    other planets gain (the load a softer planet sheds, which puts D above D_mesh); all passages
    together carry the healthy run's load (the carrier torque is constant: within a tenth of the
    deficit, the crack's ringing). The passages away from the crack carry a healthy tooth's load
    within the 2 % of that ringing: the change is there while the cracked tooth is in mesh."""
    ref = np.array([v[2] for v in healthy.values()])
    assert np.ptp(ref) < 1e-2 * ref.mean()  # the healthy teeth alike (output sampling: 0.3 %)
    sound = ref.mean()
    d_mesh, d_path = drops
    assert 0.02 < d_mesh < d_path  # a drop the run resolves above the 2 % ringing bound below
    assert set(cracked) == set(healthy)
    gain = {key: cracked[key][2] - healthy[key][2] for key in cracked}
    prev, succ = (TOOTH - 1) % Z_RING, (TOOTH + 1) % Z_RING
    near, before, others = set(), [], []
    for p in planets:
        i0, i1, got = cracked[p, TOOTH]
        assert d_mesh < 1.0 - got / sound < d_path, (p, 1.0 - got / sound, drops)
        during = {key for key, (j0, j1, _) in cracked.items() if j0 <= i1 and i0 <= j1}
        assert {(p, prev), (p, TOOTH), (p, succ)} <= during
        near |= during
        before.append(gain[p, prev])
        others.append(sum(gain[key] for key in during if key[0] != p))
        assert gain[p, prev] + gain[p, succ] > 0
    away = np.array([cracked[key][2] / healthy[key][2] - 1.0 for key in cracked if key not in near])
    assert away.size > 10 and np.abs(away).max() < 0.02
    assert min(before) > np.abs(away).max() * sound
    assert min(others) > 0
    deficit = sum(healthy[p, TOOTH][2] - cracked[p, TOOTH][2] for p in planets)
    assert abs(sum(gain.values())) < 0.1 * deficit


@pytest.fixture(scope="module")
def drops():
    cfg = load_config("mercury_1a_flexible")
    cfg.flexible.update(level=0, cutoff=100e3)
    return quasi_static_drops(cfg)


def test_a_cracked_flexible_ring_tooth_carries_less_over_a_planets_passage(drops):
    """24 mesh periods after the run-in: planet 2 passes the cracked tooth (D = 3.1 %, between
    D_mesh = 2.1 % and D_path = 3.9 %). A crack missing from the ring's FE body or on another tooth
    fails the bounds; one that acted outside its tooth's engagement, the passages away from it."""
    (cfg, healthy), (_, cracked) = _run(False, 24), _run(True, 24)
    _check(passages(cfg, healthy), passages(cfg, cracked), drops, (2,))


@pytest.mark.slow
def test_each_planet_passes_the_cracked_flexible_ring_tooth(drops):
    """The check above over 70 mesh periods: planets 2, 1 and 3 pass the cracked tooth in turn
    (a third of a carrier turn apart, the ring fault frequency N f_c), each within the bounds."""
    (cfg, healthy), (_, cracked) = _run(False, 70), _run(True, 70)
    h, c = passages(cfg, healthy), passages(cfg, cracked)
    starts = sorted((c[p, TOOTH][0], p) for p in (1, 2, 3))
    assert [p for _, p in starts] == [2, 1, 3]
    assert np.ptp(np.diff([s for s, _ in starts])) <= 2  # samples: evenly spaced
    _check(h, c, drops, (1, 2, 3))
