"""Lumped-parameter planetary model: Lin & Parker's mode structure, their closed-form planet
modes, agreement with the linearised rigid model on the same geometry, bad input."""
import dataclasses
import math
import warnings

import numpy as np
import pytest
import scipy.linalg

from flexgear.config import loads_config, preset_path
from flexgear.dynamics.assembly import build_model
from flexgear.dynamics.lumped import lin_parker_example, parameters_from_config, planetary_system
from flexgear.dynamics.modal import PLANET, ROTATIONAL, TRANSLATIONAL, linearise, modes
from flexgear.errors import ConfigError

MERCURY = preset_path("mercury_1a").read_text()
ELASTIC = (MERCURY.replace('planets = "revolute"  #', 'planets = {stiffness = 1e8}  #')
           .replace('sun = "revolute"      #', 'sun = {stiffness = 1e8}  #'))


@pytest.mark.parametrize("N", [3, 4])
def test_lin_parker_mode_structure(N):
    """3 (N + 3) coordinates: 6 rotational modes (multiplicity 1, one rigid-body mode since sun
    and carrier turn freely), 6 translational pairs, and 3 planet modes of multiplicity N - 3."""
    res = modes(planetary_system(lin_parker_example(N)))
    assert len(res.frequencies) == 3 * (N + 3)
    assert np.all(res.type_purity > 1 - 1e-9)
    assert res.mode_type.count(ROTATIONAL) == 6
    assert res.mode_type.count(TRANSLATIONAL) == 12
    assert res.mode_type.count(PLANET) == 3 * (N - 3)
    assert np.count_nonzero(res.frequencies == 0.0) == 1
    for t, m in zip(res.mode_type, res.multiplicity):
        assert m == {ROTATIONAL: 1, TRANSLATIONAL: 2, PLANET: N - 3}[t]
    # Lin & Parker's mode properties: rotational modes do not translate the central members,
    # translational modes do not rotate them, planet modes leave them still
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
    with pytest.raises(ConfigError, match=r"lumped\.planets = 6: the carrier radius"):
        planetary_system(lin_parker_example(6))
    with pytest.raises(ConfigError, match="alpha_ring"):
        planetary_system(dataclasses.replace(p, alpha_ring=math.radians(95)))


def test_eigen_solution_is_mass_orthogonal():
    sysl = planetary_system(lin_parker_example(4))
    res = modes(sysl)
    assert np.allclose(res.shapes.T @ sysl.M @ res.shapes, np.eye(sysl.n), atol=1e-10)
    w2 = scipy.linalg.eigvalsh(sysl.K, sysl.M)
    assert np.allclose(np.sort(np.clip(w2, 0, None)), res.eigenvalues, atol=1e-6 * w2.max())
