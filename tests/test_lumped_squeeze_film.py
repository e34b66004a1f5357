"""Squeeze-film mesh damping in the lumped model (issue 24 item 3, ``model = "lumped"`` with
``[lubrication] damping = "squeeze_film"``, flexgear.dynamics.lumped.friction.film_meshes): the
mesh damping against the closed form at a prescribed state, its load slope in the step's tangent
against finite differences, the [contact] damping replaced (not added to), the outputs, the
time-step convergence of a run with the film and its energy balance.

The closed form is the one of tests/test_squeeze_film.py, written out here again: per tooth pair
c = 3 sqrt(2) pi eta L (R / h_c)^(3/2) at the central film thickness of Dowson & Toyoda (1979),
h_c = 3.06 R U^0.69 G^0.56 W^-0.10, U = eta u_e / (E' R), G = alpha E', W = w / (E' R), with the
pair's relative radius R and entrainment speed u_e from the involute's radii of curvature at its
contact position on the line of action (rho_a = r_b,a tan alpha_w + s, rho_b = r_b,b tan alpha_w
- s for an external pair), and its share w = F_e / (n L) of the elastic mesh force; the mesh's
damping is the sum over its n pairs."""
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.config import loads_config, preset_path
from flexgear.config.faults import mesh_pairs
from flexgear.dynamics.lumped.friction import (film_damping, film_meshes, film_table, kernel_table, pair_positions,
                                              place_pairs)
from flexgear.dynamics.lumped.model import build_lumped
from flexgear.dynamics.lumped.time_loop import LumpedSystem, friction_state, simulate_lumped
from flexgear.results.store import load, save
from test_lumped_friction import table_powers

SPUR = ('model = "lumped"\n' + preset_path("spur_pair").read_text()).replace(
    "damping = 3000.0 ", "damping_ratio = 0.05 ")
ETA = 0.0235  # Pa s: ISO VG 100 at 70 degC
ALPHA = 2.0e-8  # 1/Pa
E, NU = 2.1e11, 0.3  # Pa, -: the preset's steel
FILM = f'damping = "squeeze_film"\nviscosity = {ETA}\npressure_viscosity = {ALPHA}\n'


def _cfg(lub=FILM + "friction_coefficient = 0.0\n", damping_ratio=0.05):
    text = SPUR.replace("damping_ratio = 0.05 ", f"damping_ratio = {damping_ratio} ")
    return loads_config(text + ("\n[lubrication]\n" + lub if lub else ""))


def _closed_form(cfg, s, omega, Fe):
    """The mesh's film damping [N s/m]: the sum over the pairs at contact positions ``s`` [m] of
    the closed form (module docstring) at pinion speed ``omega`` [rad/s] and elastic force Fe [N]."""
    _, _, pair = mesh_pairs(cfg)["pinion-wheel"]
    g1, g2, tw, L = pair.g1, pair.g2, math.tan(pair.alpha_w), pair.face_width
    e_prime = E / (1.0 - NU ** 2)
    w = Fe / (len(s) * L)
    total = 0.0
    for sj in s:
        rho_a, rho_b = g1.rb * tw + sj, g2.rb * tw - sj
        R = rho_a * rho_b / (rho_a + rho_b)
        ue = 0.5 * (omega * rho_a + omega * g1.z / g2.z * rho_b)
        h = 3.06 * R * (ETA * ue / (e_prime * R)) ** 0.69 * (ALPHA * e_prime) ** 0.56 * (w / (e_prime * R)) ** -0.10
        total += 3.0 * math.sqrt(2.0) * math.pi * ETA * L * (R / h) ** 1.5
    return total


def _kernel_state(lm, phi, omega, Fe, rate):
    """The spur pair's mesh at table position ``phi``, pinion speed ``omega``, elastic force
    ``Fe`` and deflection rate ``rate`` [m/s] (drive flank): its film damping at any elastic force
    (a function), the pairs (a FrictionWork), the damping and the relative tangent stiffness
    change :func:`film_meshes` gives, and the pairs' positions."""
    fr = kernel_table(lm.friction, np.full(2, omega), 1, 1e-3)
    G = np.ascontiguousarray(lm.G)
    n, nm = G.shape[1], G.shape[0]
    work = friction_state(np.zeros(n), np.zeros(n), np.zeros(n), nm, np.zeros(4, np.int64)).work
    place_pairs(fr, phi, omega, work)
    kk, ee, cc = lm.k[:, :1].ravel().copy(), lm.e[:, :1].ravel().copy(), lm.c[:, :1].ravel().copy()
    q = np.linalg.lstsq(G, ee + Fe / kk, rcond=None)[0]
    v = np.linalg.lstsq(G, np.full(nm, rate), rcond=None)[0]
    system = LumpedSystem(np.eye(n), np.zeros((n, n)), np.zeros((n, n)), G, np.zeros(nm))
    film = film_table(lm.friction)
    film_meshes(fr, film, system, q, v, kk, ee, cc, np.ones(nm, np.int64), omega, work)
    return (lambda Fe: film_damping(fr, film, 0, Fe, omega, work), work, film.damp[0], film.kt[0] / kk[0] - 1.0,
            pair_positions(lm.friction, 0, np.array([phi]))[0])


@pytest.mark.parametrize("phi", [0.1, 0.6])
def test_mesh_damping_is_the_closed_form(phi):
    """At a prescribed state (elastic mesh force 8 kN, pinion at 10 Hz) the damping the film
    gives the mesh is the closed form summed over the pairs on the path of contact (1e-4), one
    or two of them depending on the mesh position; the [contact] damping plays no part; no load,
    no film."""
    cfg = _cfg()
    lm = build_lumped(cfg)
    omega = 2.0 * math.pi * 10.0
    damping, work, c, _, s = _kernel_state(lm, phi, omega, 8000.0, 0.01)
    s = s[np.isfinite(s)]
    assert work.count[0] == len(s) >= 1
    # 1e-4: the lumped model's line of action is the contact normal at the reference position, its
    # angle within 2e-5 rad of the involute's operating pressure angle the closed form takes
    assert c == pytest.approx(_closed_form(cfg, s, omega, 8000.0), rel=1e-4)
    assert c > 20.0 * lm.c.max()  # about 5e4 N s/m a pair: two orders above the damping ratio's
    assert damping(0.0) == (0.0, 0.0)


def test_load_slope_of_the_tangent_is_the_derivative():
    """The step's tangent stiffness carries the film force's change with the load, kt = kk (1 +
    d(delta)/dt dc/dF_e): dc/dF_e against central differences of the film damping (1e-6)."""
    lm = build_lumped(_cfg())
    omega = 2.0 * math.pi * 10.0
    rate = 0.02
    damping, _, _, slope, _ = _kernel_state(lm, 0.3, omega, 8000.0, rate)
    dF = 1.0
    up, down = damping(8000.0 + dF)[0], damping(8000.0 - dF)[0]
    assert slope / rate == pytest.approx((up - down) / (2.0 * dF), rel=1e-6)
    assert slope > 0.0  # c ~ w^0.15: a heavier load, a thinner film, a stiffer damper


def _run(cfg, duration=0.05, run_in=0.2):
    cfg.simulation.update(duration=duration, run_in=run_in)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return flexgear.run(cfg)


def test_squeeze_film_replaces_the_mesh_damping(tmp_path):
    """With the film the [contact] damping plays no part on the drive flank: runs with damping
    ratios 0.05 and 0.5 are equal bit for bit (no back-flank contact here), and differ from the
    run without the film; the result carries the film's power and force, written and read back,
    with the film force the normal force minus its elastic part."""
    film = _run(_cfg())
    heavy = _run(_cfg(damping_ratio=0.5))
    plain = _run(_cfg(lub=""))
    m, mh, mp = (r.meshes["pinion-wheel"] for r in (film, heavy, plain))
    assert np.all(m.normal_force > 0.0)
    for f in ("normal_force", "force_global", "damping_power", "pair_damping_force"):
        assert np.array_equal(getattr(m, f), getattr(mh, f))
    assert not np.array_equal(m.normal_force, mp.normal_force)
    assert mp.damping_power is None and m.friction_force is None
    assert np.all(m.pair_damping_force[:, 1:] == 0.0) and np.any(m.pair_damping_force[:, 0] != 0.0)
    assert m.damping_power.mean() > 0.0
    back = load(save(film, tmp_path / "film.h5")).meshes["pinion-wheel"]
    for f in ("damping_power", "pair_damping_force"):
        assert np.array_equal(getattr(back, f), getattr(m, f))


def test_runs_with_and_without_films_share_one_compiled_friction_loop():
    """The friction time loop takes an empty FilmTable without films (``film_table``), so a run with
    a squeeze film and one with friction alone are one compiled signature, not two compiles; the
    friction-alone run records no film."""
    from flexgear.dynamics.lumped.time_loop import integrate_lumped_friction

    film = _run(_cfg(), duration=0.01, run_in=0.01)
    rubs = _run(_cfg(lub="friction_coefficient = 0.05\n"), duration=0.01, run_in=0.01)
    assert film.meshes["pinion-wheel"].damping_power is not None
    assert rubs.meshes["pinion-wheel"].damping_power is None
    assert rubs.meshes["pinion-wheel"].friction_force is not None
    assert len(integrate_lumped_friction.overloads) == 1


def test_film_run_converges_in_the_time_step():
    """The mesh deflection (continuous: the state, where the film's force jumps) and the film's
    mean power over the same ten mesh cycles converge as the step halves (320, 640, 1280 steps a
    mesh cycle, about 13, 6.5, 3.3 us), at least at first order: each change at the coarse run's
    sample times at least 1.8 times smaller than the one before, the last below 0.2 % of the
    deflection's ripple. First order, not HHT-alpha's second: the film's damping jumps by a
    pair's share where a pair enters or leaves the path of contact, which the step takes at its
    end (the frictionless run here converges at second order)."""
    lm = build_lumped(_cfg())
    T = 1.0 / lm.model.attrs["mesh_frequency"]
    depth, power = [], []
    for steps in (320, 640, 1280):
        h = T / steps
        integ = simulate_lumped(lm, 0.25, h, 1, alpha=-0.1)
        i0 = round(0.2 / h)
        k = steps // 320
        depth.append(integ.pair_f[i0 + k - 1:i0 + 10 * steps:k, 0, 0, 1])
        power.append(integ.damping["power"][i0:i0 + 10 * steps, 0].mean())
    d1, d2 = (np.abs(depth[i + 1] - depth[i]).max() for i in (0, 1))
    assert d1 > 1.8 * d2 and d2 < 2e-3 * np.ptp(depth[2]), (d1, d2, np.ptp(depth[2]))
    p1, p2 = abs(power[1] - power[0]), abs(power[2] - power[1])
    assert p1 > 1.8 * p2 and p2 < 1e-4 * power[2], power


MERCURY = ('model = "lumped"\n' + preset_path("mercury_1a").read_text()).replace(
    "damping = 3000.0", "damping_ratio = 0.05")


@pytest.mark.parametrize("text, load_body, torque", [(SPUR, "wheel", 200.0), (MERCURY, "carrier", 60.0)],
                         ids=["spur", "mercury_1a"])
def test_energy_balance_with_the_work_on_the_stiffness_variation(text, load_body, torque):
    """In steady state, over twenty whole mesh cycles, friction off: the input minus the output
    power plus the power the meshes' time-varying stiffness and offset put into the vibration,
    P_k = sum over the meshes of mean(1/2 dk/dt delta^2 - k delta de/dt) (k(phi), e(phi) the
    mesh tables at the drive's position, delta the deflection beyond the offset), equals the
    power the films dissipate, within 0.5 % of it plus 2e-6 of the transmitted power: the lumped
    model's input minus output power holds about 1.6e-6 of the power through the set that is no
    dissipation (MERCURY 1-A, the same with the damping ratio's mesh damping instead of the film:
    the drive arm and the speed ratio of the lumped geometry, whose line of action is the contact
    normal found at the reference position). The lumped drive torque is the mesh forces'
    moment, without P_k: the parametric excitation sustains the vibration the films damp (on the
    spur pair about 500 times the input minus output power). MERCURY 1-A: sun driven, carrier
    loaded, three planets, sun-planet and planet-ring (internal) meshes."""
    lm = build_lumped(loads_config(text + "\n[lubrication]\n" + FILM + "friction_coefficient = 0.0\n"))
    T = 1.0 / lm.model.attrs["mesh_frequency"]
    steps = 320
    h = T / steps
    integ = simulate_lumped(lm, 0.3, h, 1, alpha=-0.1)
    sl = slice(round(0.2 / h), round(0.2 / h) + 20 * steps)
    drive = lm.drive
    p_k, _ = table_powers(lm, integ, h, sl)  # the film replaces the mesh damper: P_c is not dissipated
    out = [b.name for b in lm.model.bodies].index(load_body)
    p_in = np.mean(integ.body[sl, drive, 6] * integ.body[sl, drive, 5])
    p_out = np.mean(torque * np.abs(integ.body[sl, out, 5]))
    p_film = integ.damping["power"][sl].sum(axis=1).mean()
    assert np.all(integ.mesh[sl, :, 0] >= 0.0)  # drive flanks only: the film everywhere
    assert p_film > 50.0 * 2e-6 * p_in  # the check is on the film, not on the slack
    assert abs(p_in - p_out + p_k - p_film) < 0.005 * p_film + 2e-6 * p_in
