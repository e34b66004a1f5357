"""Lumped-parameter planetary model: Lin & Parker's mode structure, their closed-form planet
modes, agreement with the linearised rigid model on the same geometry, bad input."""
import dataclasses
import math
import warnings

import numpy as np
import pytest
import scipy.linalg

from flexgear.config import loads_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.lumped.planetary import (cooley_parker_example, lin_parker_example, parameters_from_config,
                                                planetary_system)
from flexgear.dynamics.modal.system import PLANET, ROTATIONAL, TRANSLATIONAL, modes
from flexgear.dynamics.modal.linearise import linearise
from flexgear.errors import ConfigError

MERCURY = preset_path("mercury_1a").read_text()
ELASTIC = (MERCURY.replace('planets = "revolute"  #', 'planets = {stiffness = 1e8}  #')
           .replace('sun = "revolute"      #', 'sun = {stiffness = 1e8}  #'))


# Natural frequencies printed for the example systems: Lin & Parker (1999) [Hz] and Cooley &
# Parker (2012, zero carrier speed) [units of sqrt(k_p / m_p)]: rotational modes, the
# translational pairs (each listed once), the planet modes (each of multiplicity N - 3).
LIN_PARKER = {
    3: ([0.0, 1475.7, 1930.3, 2658.3, 7462.8, 11775.3], [743.2, 1102.4, 1896.0, 2276.4, 6986.3, 9647.9], []),
    4: ([0.0, 1536.6, 1970.6, 2625.7, 7773.6, 13071.1], [727.0, 1091.0, 1892.8, 2342.5, 7189.9, 10437.6],
        [1808.2, 5963.8, 6981.7]),
    5: ([0.0, 1567.4, 2006.1, 2614.8, 8065.4, 14253.1], [710.0, 1072.0, 1888.1, 2425.3, 7382.4, 11172.3],
        [1808.2, 5963.8, 6981.7]),
}
COOLEY_PARKER = {
    3: ([0.9296, 1.090, 1.358, 1.931, 5.566, 7.741], [0.7432, 1.018, 1.265, 1.487, 4.976, 6.282], []),
    4: ([0.9077, 1.046, 1.317, 2.013, 5.809, 8.383], [0.7199, 1.001, 1.317, 1.481, 5.153, 6.488],
        [0.9617, 4.320, 5.672]),
    5: ([0.8802, 1.019, 1.281, 2.090, 6.030, 8.986], [0.6992, 0.9863, 1.344, 1.496, 5.317, 6.693],
        [0.9617, 4.320, 5.672]),
}


def published_modes(table, N):
    rot, trans, planet = table[N]
    return sorted([(f, ROTATIONAL) for f in rot] + [(f, TRANSLATIONAL) for f in trans for _ in range(2)]
                  + [(f, PLANET) for f in planet for _ in range(N - 3)])


@pytest.mark.parametrize("source, N", [("lin_parker", 3), ("lin_parker", 4), ("lin_parker", 5),
                                       ("cooley_parker", 3), ("cooley_parker", 4), ("cooley_parker", 5)])
def test_published_planetary_models(source, N):
    """Set up as printed: frequencies within 0.5 %, and each mode's type (rotational,
    translational pair, planet mode of multiplicity N - 3) as published."""
    if source == "lin_parker":
        p, scale, table = lin_parker_example(N), 1.0, LIN_PARKER
    else:
        p, scale, table = cooley_parker_example(N), math.sqrt(1e7 / 1.86) / (2 * math.pi), COOLEY_PARKER
    res = modes(planetary_system(p))
    expected = published_modes(table, N)
    assert len(res.frequencies) == len(expected) == 3 * (N + 3)
    f = res.frequencies / scale
    for i, (f_pub, t_pub) in enumerate(expected):
        assert f[i] == pytest.approx(f_pub, rel=5e-3, abs=1e-9), (i, f_pub)
    # types: compare per distinct published frequency (near-coincident modes may swap order)
    for f_pub, t_pub in expected:
        near = [t for fi, t in zip(f, res.mode_type) if abs(fi - f_pub) <= 5e-3 * max(f_pub, 1e-9) + 1e-9]
        assert t_pub in near, (f_pub, t_pub, near)
    counts = {t: res.mode_type.count(t) for t in (ROTATIONAL, TRANSLATIONAL, PLANET)}
    assert counts == {ROTATIONAL: 6, TRANSLATIONAL: 12, PLANET: 3 * (N - 3)}
    assert np.all(res.type_purity > 1 - 1e-9)
    for t, m in zip(res.mode_type, res.multiplicity):
        assert m == {ROTATIONAL: 1, TRANSLATIONAL: 2, PLANET: N - 3}[t]


@pytest.mark.parametrize("N", [3, 4])
def test_mode_properties(N):
    """Lin & Parker's mode properties: rotational modes do not translate the central members,
    translational modes do not rotate them, planet modes leave them still."""
    res = modes(planetary_system(lin_parker_example(N)))
    sysl = res.system
    for i, t in enumerate(res.mode_type):
        for c in ("sun", "ring", "carrier"):
            u = sysl.bodies[c][2] @ res.shapes[:, i]
            scale = np.abs(res.shapes[:, i]).max()
            if t == ROTATIONAL:
                assert np.abs(u[:2]).max() < 1e-8 * scale
            elif t == TRANSLATIONAL:
                assert abs(u[2]) < 1e-8 * scale
            else:
                assert np.abs(u).max() < 1e-8 * scale


def test_planet_mode_frequencies_are_those_of_one_planet_between_still_members():
    """Lin & Parker: planet-mode frequencies do not depend on N and are the eigenvalues of one
    planet (zeta, eta, theta) with its two meshes and bearing, the central members held."""
    p = lin_parker_example(4)
    res = modes(planetary_system(p))
    planet_f = np.sort(res.frequencies[np.array(res.mode_type) == PLANET])
    one = dataclasses.replace(p, planets=1, held={f"{c}.{x}" for c in ("sun", "ring", "carrier") for x in "xy"}
                              | {"sun.theta", "ring.theta", "carrier.theta"})
    f_one = modes(planetary_system(one)).frequencies
    assert np.allclose(planet_f, f_one, rtol=1e-9)


def test_frequencies_do_not_depend_on_the_frame():
    p = lin_parker_example(4)
    f0 = modes(planetary_system(p)).frequencies
    f1 = modes(planetary_system(dataclasses.replace(p, first_planet_angle=1.234))).frequencies
    assert np.allclose(f0, f1, rtol=1e-9, atol=1e-6)


@pytest.mark.parametrize("text", [MERCURY, ELASTIC], ids=["rigid pins", "elastic bearings"])
def test_lumped_matches_the_linearised_rigid_model(text):
    """Same geometry, same mean mesh stiffness: the lumped model's frequencies agree with the
    rigid model's linearisation (contact normals from the real outlines) within 0.1 %."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(text)
        rigid = linearise(build_model(cfg), n_positions=6)
    ks = rigid.attrs["mesh_stiffness"]
    lumped = planetary_system(parameters_from_config(cfg, ks["sun-planet1"], ks["planet1-ring"]))
    f_r, f_l = modes(rigid).frequencies, modes(lumped).frequencies
    assert len(f_r) == len(f_l)
    assert np.allclose(f_l, f_r, rtol=1e-3)
    assert modes(lumped).mode_type == modes(rigid).mode_type


def test_bad_parameters_name_the_key():
    p = lin_parker_example(3)
    with pytest.raises(ConfigError, match=r"lumped\.planet\.mass = -1.0: must be > 0"):
        planetary_system(dataclasses.replace(p, planet=dataclasses.replace(p.planet, mass=-1.0)))
    with pytest.raises(ConfigError, match=r"lumped\.k_sun_planet = 0.0: must be > 0"):
        planetary_system(dataclasses.replace(p, k_sun_planet=0.0))
    with pytest.raises(ConfigError, match=r"lumped\.planets = 6: planets 1 and 2 collide"):
        planetary_system(lin_parker_example(6))  # 5 fit (published), 6 overlap
    with pytest.raises(ConfigError, match="alpha_ring"):
        planetary_system(dataclasses.replace(p, alpha_ring=math.radians(95)))


def test_eigen_solution_is_mass_orthogonal():
    sysl = planetary_system(lin_parker_example(4))
    res = modes(sysl)
    assert np.allclose(res.shapes.T @ sysl.M @ res.shapes, np.eye(sysl.n), atol=1e-10)
    w2 = scipy.linalg.eigvalsh(sysl.K, sysl.M)
    assert np.allclose(np.sort(np.clip(w2, 0, None)), res.eigenvalues, atol=1e-6 * w2.max())


def test_a_lumped_mesh_damped_far_above_critical_by_the_contact_law_is_warned_about():
    """The spur preset's ADAMS damper, taken at its static penetration, is tens of times critical
    on the lumped mesh (the lumped model chatters at contact loss with it, and diverges at 1.5 times
    the torque): a warning naming the mesh, the ratio and the way out; MERCURY 1-A's (0.3) and a
    given damping ratio are not warned about."""
    import warnings

    from flexgear.config import load_config
    from flexgear.dynamics.lumped.model import OVERDAMPED, build_lumped

    with pytest.warns(UserWarning, match=r"mesh pinion-wheel: \[contact\] C gives the lumped mesh a damping ratio "
                      r"of (\d+\.?\d*) .*give \[contact\] damping_ratio") as rec:
        build_lumped(load_config("spur_pair:lumped"))
    ratio = float(str(rec[0].message).split("damping ratio of ")[1].split()[0])
    assert ratio > OVERDAMPED
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        build_lumped(load_config("mercury_1a:lumped"))
        build_lumped(load_config("spur_pair:lumped").use_damping_ratio(0.05))
