"""Engagement geometry and characteristic fault frequencies, against independent kinematic counts:
the rate at which one tooth engages, counted from the rigid gear angles over a long window."""
import math
import warnings

import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.config.faults import contact_ratio_at, set_kinematics
from flexgear.gears.faults import LEFT, Eccentricity
from flexgear.gears.geometry import GearPair
from flexgear.gears.kinematics import (contact_roll_range, fault_lines, flank_roll_angle, hunting_tooth_frequency,
                                       in_mesh, line_of_action, local_fault_frequency, mate_flank)
from flexgear.gears.modified import ToothOffset


@pytest.fixture(scope="module")
def planetary():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_config("mercury_1a")


@pytest.fixture(scope="module")
def spur():
    return load_config("spur_pair")


def rising(x):
    """Number of False -> True transitions of a boolean series."""
    return int(np.count_nonzero(x[1:] & ~x[:-1]))


def test_roll_ranges_span_the_path_of_contact(planetary):
    for pair in (GearPair(planetary.gears["sun"], planetary.gears["planet"]),
                 GearPair(planetary.gears["planet"], planetary.gears["ring"])):
        (a1, b1), (a2, b2) = contact_roll_range(pair)
        g_alpha = sum(pair.path_of_contact)
        assert (b1 - a1) * pair.g1.rb == pytest.approx(g_alpha) and (b2 - a2) * pair.g2.rb == pytest.approx(g_alpha)
        assert pair.g1.rb * math.hypot(1, b1) == pytest.approx(pair.g1.ra)  # recess ends at gear 1's tip
        tip2 = a2 if pair.internal else b2  # the ring's tip is its smallest roll angle
        assert pair.g2.rb * math.hypot(1, tip2) == pytest.approx(pair.g2.ra)
        assert contact_ratio_at(pair, pair.centre_distance) == pytest.approx(pair.contact_ratio)
        assert contact_ratio_at(pair, pair.centre_distance + (-1 if pair.internal else 1) * 0.2e-3) < pair.contact_ratio


def planetary_angles(cfg, t):
    """Rigid angles at times t: sun, planets (absolute), planet centre directions; ring fixed."""
    kin = set_kinematics(cfg)
    N = cfg.planetary["planets"]
    psi0 = math.radians(cfg.planetary["first_planet_angle_deg"])
    th_s = 0.3 + 2 * np.pi * kin.rotation["sun"] * t
    psi = [psi0 + 2 * np.pi * k / N + 2 * np.pi * kin.carrier * t for k in range(N)]
    th_p = [1.1 * k + 2 * np.pi * kin.rotation["planet"] * t for k in range(N)]
    return kin, th_s, psi, th_p


def test_local_fault_frequencies_of_a_planetary_set_count(planetary):
    """Feng & Zuo (2012): sun N f_m / z_s, planet f_m / z_p per flank (2 f_m / z_p both), ring
    N f_c, each the counted rate of engagements of one tooth's loaded flank over 30 carrier turns."""
    cfg = planetary
    s, p, r = (cfg.gears[n] for n in ("sun", "planet", "ring"))
    sp, pr = GearPair(s, p), GearPair(p, r)
    kin = set_kinematics(cfg)
    T = 30 / kin.carrier
    t = np.arange(0.0, T, 1 / (200 * kin.mesh))
    kin, th_s, psi, th_p = planetary_angles(cfg, t)
    (rs, rp_s), (rp_r, rr) = contact_roll_range(sp), contact_roll_range(pr)
    side_s = LEFT  # the sun's loaded flank (drive sun counter-clockwise, loaded carrier)
    side_p_sun = mate_flank(side_s, False)
    side_p_ring = -side_p_sun
    side_r = mate_flank(side_p_ring, True)
    counts = dict(sun=0, planet_sun=0, planet_ring=0, ring=0)
    for k in range(cfg.planetary["planets"]):
        ga_sp, gb_sp = line_of_action(sp, psi[k], side_s)
        ga_pr, gb_pr = line_of_action(pr, psi[k], side_p_ring)
        counts["sun"] += rising(in_mesh(s, 5, side_s, th_s, ga_sp, rs))
        counts["ring"] += rising(in_mesh(r, 40, side_r, 0.0, gb_pr, rr))
        if k == 0:
            counts["planet_sun"] += rising(in_mesh(p, 7, side_p_sun, th_p[k], gb_sp, rp_s))
            counts["planet_ring"] += rising(in_mesh(p, 7, side_p_ring, th_p[k], ga_pr, rp_r))
    tol = 1.5 / T
    assert counts["sun"] / T == pytest.approx(local_fault_frequency(kin, "sun"), abs=tol)
    assert counts["ring"] / T == pytest.approx(local_fault_frequency(kin, "ring"), abs=tol)
    assert counts["planet_sun"] / T == pytest.approx(local_fault_frequency(kin, "planet"), abs=tol)
    assert counts["planet_ring"] / T == pytest.approx(local_fault_frequency(kin, "planet"), abs=tol)
    both = counts["planet_sun"] + counts["planet_ring"]
    assert both / T == pytest.approx(local_fault_frequency(kin, "planet", both_flanks=True), abs=2 * tol)
    # the published closed forms
    fm, fc, N = kin.mesh, kin.carrier, cfg.planetary["planets"]
    assert local_fault_frequency(kin, "sun") == pytest.approx(N * fm / s.z)
    assert local_fault_frequency(kin, "ring") == pytest.approx(N * fc)
    assert fm == pytest.approx(r.z * fc)


def test_spur_fault_and_hunting_tooth_frequencies_count(spur):
    cfg = spur
    g1, g2 = cfg.gears["pinion"], cfg.gears["wheel"]
    pair = GearPair(g1, g2)
    kin = set_kinematics(cfg)
    T = 200 / kin.relative("pinion")
    t = np.arange(0.0, T, 1 / (100 * kin.mesh))
    r1, r2 = contact_roll_range(pair)
    ga, gb = line_of_action(pair, 0.0, LEFT)
    # a meshing start: tooth 0 of the pinion and tooth 0 of the wheel touch on the line of action,
    # where their roll lengths add up to its length between the base circles, a sin(alpha_w)
    xi1 = float(flank_roll_angle(g1, 0, LEFT, 0.2, ga))
    xi2 = (pair.centre_distance * math.sin(pair.alpha_w) - g1.rb * xi1) / g2.rb
    th20 = xi2 - float(g2.involute_half_angle(g2.rb)) + float(gb)  # solves flank_roll_angle(g2, 0, LEFT, th20, gb) = xi2
    assert float(flank_roll_angle(g2, 0, LEFT, th20, gb)) == pytest.approx(xi2)
    th1 = 0.2 + 2 * np.pi * kin.rotation["pinion"] * t
    th2 = th20 + 2 * np.pi * kin.rotation["wheel"] * t
    e1 = in_mesh(g1, 3, LEFT, th1, ga, r1)
    e2 = in_mesh(g2, 11, LEFT, th2, gb, r2)
    tol = 1.5 / T
    assert rising(e1) / T == pytest.approx(local_fault_frequency(kin, "pinion"), abs=tol)
    assert rising(e2) / T == pytest.approx(local_fault_frequency(kin, "wheel"), abs=tol)
    # one pinion tooth meets the same wheel tooth (one of the 7 it can meet) every lcm(z1, z2) meshes
    together = max(rising(e1 & in_mesh(g2, j, LEFT, th2, gb, r2)) for j in range(g2.z))
    assert together / T == pytest.approx(hunting_tooth_frequency(kin), abs=tol)


@pytest.mark.parametrize("body", ["sun", "planet", "ring"])
def test_eccentricity_modulates_at_the_rotation_relative_to_the_carrier(planetary, body):
    """The run-out of a gear moves its flank along a mesh's line of action; the dominant line of
    that displacement is the sideband spacing of fault_lines('distributed')."""
    cfg = planetary
    kin = set_kinematics(cfg)
    T = 40 / kin.carrier
    t = np.arange(0.0, T, 1 / 2000.0)
    kin, th_s, psi, th_p = planetary_angles(cfg, t)
    theta = {"sun": th_s, "planet": th_p[0], "ring": np.zeros_like(t)}[body]
    e = Eccentricity(magnitude=10e-6, phase=0.7)
    shift = e.shift()
    # the toothing's offset turns with the gear; the line of action (sun-planet 1 for the sun and
    # planet, planet 1-ring for the ring) turns with the carrier
    pair = (GearPair(cfg.gears["sun"], cfg.gears["planet"]) if body != "ring"
            else GearPair(cfg.gears["planet"], cfg.gears["ring"]))
    gamma = line_of_action(pair, psi[0], LEFT)[0]
    n = np.stack([-np.sin(gamma), np.cos(gamma)], axis=-1)  # direction of the line of action
    u = np.array([(ToothOffset(0.0, tuple(_rot(shift, a))).displacement([0.0, 0.0]) @ nn) for a, nn in zip(theta, n)])
    spec = np.abs(np.fft.rfft(u - u.mean()))
    f = np.fft.rfftfreq(len(u), t[1] - t[0])
    peak = f[np.argmax(spec)]
    expected = fault_lines(kin, body, "distributed", harmonics=1, sidebands=0)[0].freq
    assert peak == pytest.approx(expected, abs=1.5 / T)
    assert expected == pytest.approx(kin.relative(body))


def _rot(v, a):
    return (v[0] * math.cos(a) - v[1] * math.sin(a), v[0] * math.sin(a) + v[1] * math.cos(a))


def test_fault_lines_labels(planetary):
    kin = set_kinematics(planetary)
    lines = fault_lines(kin, "sun")
    ff = local_fault_frequency(kin, "sun")
    by = {ln.label: ln.freq for ln in lines}
    assert by["f_f"] == pytest.approx(ff) and by["3f_f"] == pytest.approx(3 * ff)
    assert by["f_m-f_f"] == pytest.approx(kin.mesh - ff) and by["2f_m+2f_f"] == pytest.approx(2 * kin.mesh + 2 * ff)
    assert [ln.freq for ln in lines] == sorted(ln.freq for ln in lines)
    with pytest.raises(ValueError, match="'local' or 'distributed'"):
        fault_lines(kin, "sun", "global")
