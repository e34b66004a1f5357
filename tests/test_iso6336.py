"""ISO 6336-1 method B tooth stiffness: published worked values and closed-form checks."""
import math

import pytest

from flexgear.errors import ConfigError
from flexgear.stiffness.iso6336 import (C_COEFFS, N_PER_MM_UM, basic_rack_factor, from_iso_units,
                              gear_blank_factor, mesh_stiffness, pair_stiffness, q_prime,
                              single_stiffness, to_iso_units, transverse_contact_ratio,
                              virtual_teeth)


def test_iso_tr_6336_30_worked_example():
    """ISO/TR 6336-30:2017 example: z 17/103, m_n 8, beta 15.8 deg, x 0.145/0, rack h_fP 1.4 m_n.

    Published: z_n1 = 18.905, z_n2 = 114.543, c'_th = 17.856 N/(mm um), c' = 12.370 N/(mm um).
    """
    s = single_stiffness(17, 103, 0.145, 0.0, beta=math.radians(15.8), h_fP=1.4)
    assert s.z_n1 == pytest.approx(18.905, abs=1e-3)
    assert s.z_n2 == pytest.approx(114.543, abs=1e-3)
    assert s.c_th_iso == pytest.approx(17.856, abs=2e-3)
    assert s.c_prime_iso == pytest.approx(12.370, abs=2e-3)
    # and the published C_B of that rack: 1 + 0.5 (1.2 - 1.4) = 0.9
    assert s.C_B == pytest.approx(0.9, abs=1e-12)


def test_units():
    # 1 N/(mm um) = 1 N / (1e-3 m * 1e-6 m) = 1e9 N/m^2
    assert N_PER_MM_UM == 1e9
    assert to_iso_units(from_iso_units(14.0)) == pytest.approx(14.0)
    s = single_stiffness(24, 21)
    assert s.c_prime == pytest.approx(s.c_prime_iso * 1e9)


def test_rack_limit_and_cth_is_inverse_q():
    # z -> infinity, x = 0: q' -> C1, c'_th -> 1/C1 = 21.17 N/(mm um)
    assert q_prime(math.inf, math.inf) == pytest.approx(C_COEFFS[0])
    s = single_stiffness(10**7, 10**7 + 1)
    assert s.c_th_iso == pytest.approx(1.0 / C_COEFFS[0], rel=1e-5)
    s = single_stiffness(24, 21)
    assert s.c_th_iso * s.q_prime == pytest.approx(1.0)


def test_standard_pair_hand_computation():
    """24/21, x = 0, standard rack: pinion is the 21-tooth gear.

    q' = 0.04723 + 0.15551/21 + 0.25791/24 = 0.065381 mm um/N -> c'_th = 15.295;
    c' = 15.295 * 0.8 * 1 * 0.975 = 11.930 N/(mm um).
    """
    s = single_stiffness(24, 21)
    assert s.q_prime == pytest.approx(0.065381, abs=2e-6)
    assert s.c_th_iso == pytest.approx(15.295, abs=2e-3)
    assert s.C_B == pytest.approx(0.975)
    assert s.C_M == 0.8 and s.C_R == 1.0
    assert s.c_prime_iso == pytest.approx(11.930, abs=2e-3)
    # order of the arguments does not matter for an external pair
    assert single_stiffness(21, 24).c_prime == pytest.approx(s.c_prime)
    # ISO's "if no better value" figure for standard solid steel gears is c' ~ 14 N/(mm um);
    # standard gears with 17..100 teeth lie within about 20 % of it
    for z1, z2 in [(17, 40), (24, 21), (30, 90), (60, 100)]:
        assert 0.8 * 14 < single_stiffness(z1, z2).c_prime_iso < 1.2 * 14


def test_internal_gear_uses_zn2_infinite():
    s = single_stiffness(21, 66, internal=True)
    assert math.isinf(s.z_n2)
    # q' = C1 + C2/21 (C3/z_n2 vanishes) = 0.054635 -> c'_th = 18.303
    assert s.q_prime == pytest.approx(0.04723 + 0.15551 / 21, rel=1e-12)
    assert s.c_th_iso == pytest.approx(18.303, abs=2e-3)
    # an internal mesh is stiffer than the external mesh with a ring of the same tooth count
    assert s.c_prime > single_stiffness(21, 66).c_prime
    with pytest.raises(ConfigError):
        single_stiffness(66, 21, internal=True)


def test_factors():
    assert basic_rack_factor(1.25, math.radians(20)) == pytest.approx(0.975)
    assert basic_rack_factor(1.2, math.radians(20)) == pytest.approx(1.0)
    assert basic_rack_factor(1.2, math.radians(25)) == pytest.approx(1.1)
    assert gear_blank_factor() == 1.0
    # C_R = 1 + ln(b_s/b)/(5 exp(s_R/(5 m_n)))
    assert gear_blank_factor(0.5, 5.0) == pytest.approx(1 + math.log(0.5) / (5 * math.e))
    with pytest.raises(ConfigError):
        gear_blank_factor(0.1, 5.0)


def test_low_load_reduction():
    s_nom = single_stiffness(24, 21)
    s_hi = single_stiffness(24, 21, line_load=2e5)
    s_lo = single_stiffness(24, 21, line_load=1e4)  # 10 N/mm
    assert s_hi.c_prime == pytest.approx(s_nom.c_prime)
    assert s_lo.c_prime == pytest.approx(s_nom.c_prime * 0.1 ** 0.25)


def test_virtual_teeth_spur_and_helical():
    assert virtual_teeth(24, 0.0) == 24
    b = math.radians(20)
    bb = math.asin(math.sin(b) * math.cos(math.radians(20)))
    assert virtual_teeth(24, b) == pytest.approx(24 / (math.cos(bb) ** 2 * math.cos(b)))


def test_contact_ratio_reference_values():
    # ISO 21771 closed form (docs/paper_parameters.md): 1.586 sun-planet, 1.932 planet-ring
    assert transverse_contact_ratio(24, 21, 2e-3) == pytest.approx(1.586, abs=1e-3)
    assert transverse_contact_ratio(21, 66, 2e-3, internal=True) == pytest.approx(1.932, abs=1e-3)


def test_mesh_stiffness_formula():
    assert mesh_stiffness(14.0, 1.0) == pytest.approx(14.0)
    assert mesh_stiffness(14.0, 2.0) == pytest.approx(14.0 * 1.75)
    # ISO's "if no better value": c' = 14 -> c_gamma ~ 20 N/(mm um) for eps_alpha ~ 1.57
    assert mesh_stiffness(14.0, 1.57) == pytest.approx(20.0, rel=0.02)
    with pytest.raises(ConfigError):
        mesh_stiffness(14.0, 0.9)


def test_pair_stiffness_totals():
    p = pair_stiffness(24, 21, 2e-3, 0.02)
    assert p.k_single == pytest.approx(p.c_prime * 0.02)
    assert p.k_mesh == pytest.approx(p.c_gamma_alpha * 0.02)
    assert p.c_gamma_alpha == pytest.approx(p.c_prime * (0.75 * p.eps_alpha + 0.25))
