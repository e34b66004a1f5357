"""Explicit lumped parameters in the TOML ([lumped.parameters]): a published set loaded from its
file reproduces the printed natural frequencies and mode types; the parameters replace the
geometry's in a time-domain run; bad input is refused naming the key."""
import json
import math
import warnings

import numpy as np
import pytest

import flexgear
from flexgear.app.cli import main
from flexgear.config import check_config, config_document, load_config, loads_config, parse_config, preset_path
from flexgear.dynamics.modal.system import PLANET, ROTATIONAL, TRANSLATIONAL
from flexgear.dynamics.modal.analysis import modal_analysis
from flexgear.errors import ConfigError

from test_lumped import LIN_PARKER, published_modes

LIN_PARKER_TOML = preset_path("lin_parker_1999").read_text()
MERCURY = preset_path("mercury_1a").read_text()


def _check_published(res, N):
    """Frequencies within 0.5 % of Lin & Parker (1999) and the mode types as printed."""
    expected = published_modes(LIN_PARKER, N)
    f = res.frequencies
    assert len(f) == len(expected) == 3 * (N + 3)
    for i, (f_pub, _) in enumerate(expected):
        assert f[i] == pytest.approx(f_pub, rel=5e-3, abs=1e-9), (i, f_pub)
    for f_pub, t_pub in expected:  # near-coincident modes of different types may swap order
        near = [t for fi, t in zip(f, res.mode_type) if abs(fi - f_pub) <= 5e-3 * max(f_pub, 1e-9) + 1e-9]
        assert t_pub in near, (f_pub, t_pub, near)
    counts = {t: res.mode_type.count(t) for t in (ROTATIONAL, TRANSLATIONAL, PLANET)}
    assert counts == {ROTATIONAL: 6, TRANSLATIONAL: 12, PLANET: 3 * (N - 3)}
    for t, m in zip(res.mode_type, res.multiplicity):
        assert m == {ROTATIONAL: 1, TRANSLATIONAL: 2, PLANET: N - 3}[t]


@pytest.mark.parametrize("N", [3, 4, 5])
def test_published_set_from_its_toml(N):
    """The shipped file (4 planets; 3 and 5 by changing one key) as printed by Lin & Parker."""
    cfg = loads_config(LIN_PARKER_TOML.replace("planets = 4", f"planets = {N}"))
    _check_published(modal_analysis(cfg), N)


def test_modal_command_on_the_shipped_parameter_set(tmp_path, capsys):
    out = tmp_path / "modal"
    assert main(["modal", "lin_parker_1999", "-o", str(out)]) == 0
    data = json.loads((out / "modes.json").read_text())
    expected = published_modes(LIN_PARKER, 4)
    assert np.allclose(data["frequencies"], [f for f, _ in expected], rtol=5e-3, atol=1e-6)
    text = (out / "modes.md").read_text()
    assert "planet" in text and "nan" not in text  # no operating point: no mesh force to print
    assert not (out / "campbell.png").exists()  # nor gear kinematics for a Campbell diagram


def test_printed_forms_of_inertia_and_torsional_stiffness_are_equivalent():
    """I / r^2 [kg] and I [kg m^2]; k_u on u = r theta [N/m] and k r^2 [N m/rad]; a diameter
    and a radius; planets given by their angles: the same model."""
    r_ring = 275.0e-3 / 2
    text = (LIN_PARKER_TOML.replace("inertia_over_r2 = 3.00", f"inertia = {3.00 * r_ring**2!r}")
            .replace("torsional_stiffness_u = 1.0e9", f"torsional_stiffness = {1e9 * r_ring**2!r}")
            .replace("base_diameter = 275.0e-3", f"base_radius = {r_ring!r}")
            .replace("first_planet_angle_deg = 0.0", "planet_angles_deg = [0.0, 90.0, 180.0, 270.0]"))
    assert text != LIN_PARKER_TOML
    f0 = modal_analysis(loads_config(LIN_PARKER_TOML)).frequencies
    assert np.allclose(modal_analysis(loads_config(text)).frequencies, f0, rtol=1e-12, atol=1e-9)


def test_unequal_spacing_keeps_the_frequencies_of_equal_spacing_only_when_it_is_equal():
    """Lin & Parker's structure needs equal spacing: unequal angles split the planet mode."""
    cfg = loads_config(LIN_PARKER_TOML.replace("first_planet_angle_deg = 0.0",
                                               "planet_angles_deg = [0.0, 80.0, 180.0, 270.0]"))
    f = modal_analysis(cfg).frequencies
    f_eq = modal_analysis(loads_config(LIN_PARKER_TOML)).frequencies
    assert not np.allclose(f, f_eq, rtol=1e-3)


def test_the_parameter_set_round_trips_and_refuses_a_time_domain_run(tmp_path, capsys):
    cfg = load_config("lin_parker_1999")
    again = parse_config(config_document(cfg))
    assert np.allclose(modal_analysis(again).frequencies, modal_analysis(cfg).frequencies, rtol=1e-12)
    assert check_config(cfg).lumped == cfg.lumped
    with pytest.raises(ConfigError, match=r"\[lumped.parameters\] without \[gears\].*tooth counts"):
        flexgear.run(cfg)
    out = tmp_path / "run"
    assert main(["run", "lin_parker_1999", "-o", str(out)]) == 2
    assert "tooth counts" in capsys.readouterr().err
    for command in (["info"], ["mesh", "-o", str(out)], ["modes", "-o", str(out)]):
        assert main([command[0], "lin_parker_1999"] + command[1:]) == 2
        assert "use `flexgear modal`" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("old, new, match", [
    ("mass = 0.66", "mass = -0.66", r"lumped\.parameters\.planet\.mass = -0\.66: must be > 0"),
    ("bearing_stiffness = 1.0e8     # N/m\n", "bearing_stiffness = -1.0e8\n",
     r"lumped\.parameters\.sun\.bearing_stiffness = -100000000\.0: must be > 0 N/m"),
    # README: non-positive values are errors; a planet on a free pin would be a mechanism (spurious zero modes)
    ("bearing_stiffness = 1.0e8     # N/m\n", "bearing_stiffness = 0\n",
     r"lumped\.parameters\.sun\.bearing_stiffness = 0\.0: must be > 0 N/m \(non-positive .*held"),
    ("bearing_stiffness = 1.0e8     # to the carrier pin", "bearing_stiffness = 0.0",
     r"lumped\.parameters\.planet\.bearing_stiffness = 0\.0: must be > 0 N/m"),
    ("inertia_over_r2 = 6.29", "inertia_over_r2 = 0",
     r"lumped\.parameters\.carrier\.inertia_over_r2 = 0\.0: must be > 0"),
    ("sun-planet = 5.0e8", "sun-planet = 0.0", r"lumped\.constant_stiffness\.sun-planet = 0\.0: must be > 0"),
    ("pressure_angle_deg = 24.6", "pressure_angle_deg = 95.0", r"lumped\.parameters\.pressure_angle_deg = 95\.0"),
    ("planets = 4", "planets = 6", r"lumped\.parameters\.planets = 6: planets \d and \d collide"),
    ("planets = 4", "planets = 0", r"lumped\.parameters\.planets = 0: must be an integer >= 1"),
    ("first_planet_angle_deg = 0.0", "planet_angles_deg = [0.0, 30.0, 180.0, 270.0]",
     r"lumped\.parameters\.planet_angles_deg = .*planets 1 and 2 collide"),
    ("first_planet_angle_deg = 0.0", "planet_angles_deg = [0.0, 180.0]",
     r"lumped\.parameters\.planet_angles_deg = \[0\.0, 180\.0\]: must be a list of .*4 angles"),
    ('mesh_stiffness = "constant"', 'mesh_stiffness = "fe"',
     r"lumped\.mesh_stiffness = 'fe'.*do not exist for these pairs"),
    ("sun-planet = 5.0e8,", "sun-ring = 5.0e8,", r"lumped\.constant_stiffness\.sun-ring: no such pair"),
    ("sun-planet = 5.0e8, planet-ring = 5.0e8", "sun-planet = 5.0e8",
     r"lumped\.constant_stiffness\.planet-ring is missing"),
    ("mass = 0.66\n", "", r"lumped\.parameters\.planet\.mass is missing"),
    ("base_diameter = 100.3e-3\n", "", r"lumped\.parameters\.planet\.base_radius is missing"),
    ("mass = 2.35\n", "mass = 2.35\ninertia = 0.04\n",
     r"give one of lumped\.parameters\.ring\.inertia, lumped\.parameters\.ring\.inertia_over_r2"),
    ("bearing_stiffness = 1.0e8     # to the carrier pin", "bearing_stiffness = 1.0e8\ntorsional_stiffness = 1e6",
     r"'lumped\.parameters\.planet\.torsional_stiffness'; planets turn freely"),
    ("held = []", 'held = ["planet5.theta"]', r"lumped\.parameters\.held: unknown coordinate\(s\) 'planet5\.theta'"),
    ("[lumped.parameters.carrier]", "[lumped.parameters.carier]", r"'lumped\.parameters\.carier'"),
    ('kind = "planetary"', 'kind = "spur"', r"kind = 'spur'.*planetary"),
    ("[lumped]\n", "[drive]\nbody = \"sun\"\nspeed_hz = 10.0\n[lumped]\n",
     r"'drive' given with \[lumped\.parameters\] and no \[gears\]"),
])
def test_bad_parameters_are_refused_naming_the_key(old, new, match):
    assert old in LIN_PARKER_TOML
    text = LIN_PARKER_TOML.replace(old, new, 1)
    with pytest.raises(ConfigError, match=match):
        modal_analysis(loads_config(text))


def test_a_missing_member_table_is_named():
    start = LIN_PARKER_TOML.index("[lumped.parameters.planet]")
    with pytest.raises(ConfigError, match=r"\[lumped\.parameters\.planet\] is missing"):
        loads_config(LIN_PARKER_TOML[:start])


# ---------------------------------------------------------------- with [gears]: a run on the geometry
EXPLICIT_MERCURY = MERCURY.replace('kind = "planetary"', '''kind = "planetary"
model = "lumped"
[lumped]
constant_stiffness = {sun-planet = 3.0e8, planet-ring = 3.5e8}
damping_ratio = 0.05
[lumped.parameters]
pressure_angle_deg = 21.0
[lumped.parameters.carrier]
mass = 2.0
''')


def test_explicit_parameters_on_a_gear_set_run_and_carry_the_static_load():
    """Sun driven, carrier loaded with T_c = 60 N m, rigid pins: each of the N planets carries
    T_c / a through its two meshes, whose forces act at the pressure angle given (21 deg, not
    the geometry's 20 deg): F = T_c / (2 N a cos(alpha)). The constant mesh stiffness gives no
    mesh-frequency excitation: the force is steady."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(EXPLICIT_MERCURY)
        cfg.simulation.update(run_in=0.1, duration=0.05)
        res = flexgear.run(cfg)
    a = 0.5 * 2.0e-3 * (24 + 21)  # centre distance [m] of the standard set (module 2 mm)
    expected = 60.0 / (2 * 3 * a * math.cos(math.radians(21.0)))
    for name, m in res.meshes.items():
        assert m.normal_force.mean() == pytest.approx(expected, rel=1e-6), name
        assert m.normal_force.std() < 1e-6 * expected
    assert res.bodies["carrier"].angular_velocity.mean() == pytest.approx(2 * math.pi * 30 * 24 / 90, rel=1e-6)
    assert res.attrs["model"] == "lumped"


def test_explicit_parameters_on_a_gear_set_change_the_modes_as_given():
    """Rigid pins, sun held in translation and driven, ring fixed: the coordinates are the
    carrier's and the N planets' rotations. Two rotational modes (carrier and planets in step) and
    N - 1 planet modes, in which a planet turns between still members on its two meshes:
    omega^2 = (k_sp + k_pr) r_b,planet^2 / J_planet. Every spring is a mesh, so four times the
    mesh stiffness doubles every frequency."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(EXPLICIT_MERCURY)
        base = modal_analysis(cfg)
        stiff = modal_analysis(loads_config(EXPLICIT_MERCURY.replace("sun-planet = 3.0e8, planet-ring = 3.5e8",
                                                                     "sun-planet = 1.2e9, planet-ring = 1.4e9")))
    assert np.allclose(stiff.frequencies, 2 * base.frequencies, rtol=1e-9)
    N = 3
    assert base.mode_type.count(ROTATIONAL) == 2 and base.mode_type.count(PLANET) == N - 1
    planet = cfg.gears["planet"]
    _, J = planet.mass_properties(cfg.material.rho)
    f_planet = math.sqrt((3.0e8 + 3.5e8) * planet.rb**2 / J) / (2 * math.pi)
    f = base.frequencies[np.array(base.mode_type) == PLANET]
    assert np.allclose(f, f_planet, rtol=1e-9)


@pytest.mark.parametrize("old, new, match", [
    ("[lumped.parameters]\n", "[lumped.parameters]\nplanets = 4\n",
     r"'lumped\.parameters\.planets'; with \[gears\] the planets come from \[planetary\]"),
    ("mass = 2.0\n", "mass = 2.0\nbearing_stiffness = 1e8\n",
     r"'lumped\.parameters\.carrier\.bearing_stiffness'; with \[gears\], supports come from \[supports\]"),
    ("constant_stiffness = {sun-planet = 3.0e8, planet-ring = 3.5e8}", 'mesh_stiffness = "contact"',
     r"lumped\.mesh_stiffness = 'contact': with \[lumped\.parameters\]"),
    ("mass = 2.0\n", "mass = 2.0\ninertia_over_r2 = 1.0\n",
     r"lumped\.parameters\.carrier\.inertia_over_r2 needs the member's radius"),
])
def test_bad_parameters_on_a_gear_set(old, new, match):
    assert old in EXPLICIT_MERCURY
    with pytest.raises(ConfigError, match=match):
        loads_config(EXPLICIT_MERCURY.replace(old, new, 1))
