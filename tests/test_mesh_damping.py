"""Contact damping given as a mesh damping ratio (issue 6, section 6)."""
import math
import tomllib

import pytest
import tomli_w

from flexgear.config import load_config, loads_config
from flexgear.config.mesh_damping import damping_from_ratio, equivalent_mass, ratio_from_damping
from flexgear.dynamics.model.assembly import build_model
from flexgear.errors import ConfigError
from flexgear.app.run import resolved_toml


def _spur(contact: dict, gears: dict | None = None, drive="pinion", load="wheel") -> str:
    """The spur preset as TOML text, with [contact] damping replaced by ``contact`` and the
    given gear entries added (J_wheel = 5e-5 kg m^2 by default), drive and load bodies set."""
    data = tomllib.loads(load_config("spur_pair").source_text)
    data["contact"].pop("damping")
    data["contact"].update(contact)
    for name, extra in (gears if gears is not None else {"wheel": {"inertia": 5.0e-5}}).items():
        data["gears"][name].update(extra)
    data["drive"]["body"], data["load"]["body"] = drive, load
    return tomli_w.dumps(data)


def test_spur_conversion_matches_a_hand_calculation():
    """zeta = 0.05 on the spur preset with J_wheel = 5e-5 kg m^2 given, pinion driven:
    r_b = 21 x 2 mm / 2 x cos 20 deg = 19.7335 mm; W = 200 N m / r_b = 10135.0 N;
    K = 3e5 N/mm^1.3 = 3e5 x 1000^1.3 N/m^1.3 = 2.38298e9; delta_0 = (W/K)^(1/1.3) = 73.830 um;
    k = 1.3 W / delta_0 = 1.78457e8 N/m; m_e = J / r_b^2 = 0.128398 kg (pinion held);
    c = 2 zeta sqrt(k m_e) = 478.68 N s/m; s = x^2 (3 - 2x), x = 73.830/300: 0.151886;
    C = c / s = 3151.6 N s/m."""
    cfg = loads_config(_spur({"damping_ratio": 0.05}))
    law = cfg.contact_law(cfg.pairs["pinion-wheel"])
    assert law.C == pytest.approx(3151.6, rel=1e-4)
    assert law.zeta == 0.05
    assert "damping_ratio = 0.05" in law.damping_reading
    mesh = build_model(cfg).meshes[0]
    assert mesh.C == law.C
    assert mesh.attrs["damping_ratio"] == 0.05


def test_paper_damping_is_heavily_overdamped():
    """The paper's C = 3000 N s/mm on the spur preset: zeta ~ 50 at the single-pair operating
    penetration (74 um); two pairs sharing the load (43 um each, in parallel: 2k and 2c, so
    zeta = sqrt 2 x one pair's) give ~ 28. Gear meshes have 0.03-0.1."""
    cfg = load_config("spur_pair")
    law = cfg.contact_law(cfg.pairs["pinion-wheel"])
    assert 40 < law.zeta < 60
    # two pairs sharing W: delta = (W/2K)^(1/e), tangent stiffness per pair at that penetration
    W, K, e, d = 200 / cfg.gears["wheel"].rb, law.K, law.e, law.d
    inv_m = cfg.gears["wheel"].rb ** 2 / cfg.gears["wheel"].mass_properties(cfg.material.rho)[1]
    zeta_double = math.sqrt(2) * ratio_from_damping(law.C, W / 2, K, e, d, 1 / inv_m)
    assert 20 < zeta_double < 35


def test_ratio_and_damping_are_inverse_and_scale_as_expected():
    args = dict(force=236.5, K=2.38e9, e=1.3, d=3e-4, m_e=0.117)
    C = damping_from_ratio(0.07, **args)
    assert ratio_from_damping(C, **args) == pytest.approx(0.07, rel=1e-12)
    assert damping_from_ratio(0.14, **args) == pytest.approx(2 * C, rel=1e-12)  # linear in zeta
    heavier = dict(args, m_e=4 * 0.117)
    assert damping_from_ratio(0.07, **heavier) == pytest.approx(2 * C, rel=1e-12)  # sqrt(m_e)


def test_equivalent_mass_of_free_and_held_gears():
    assert equivalent_mass([(0.02, 8e-5), (0.02, 8e-5)]) == pytest.approx(8e-5 / 0.02**2 / 2)
    assert equivalent_mass([(0.02, None), (0.01, 1e-5)]) == pytest.approx(0.1)
    with pytest.raises(ValueError, match="held"):
        equivalent_mass([(0.02, None), (0.01, math.inf)])


def test_driven_gear_is_held_the_other_counts():
    """Drive the wheel and load the pinion: m_e is now J_pinion / r_b,pinion^2."""
    cfg = loads_config(_spur({"damping_ratio": 0.05}, gears={"pinion": {"inertia": 6.0e-5}}, drive="wheel",
                             load="pinion"))
    law = cfg.contact_law(cfg.pairs["pinion-wheel"])
    assert "m_e = 0.118" in law.damping_reading  # 6e-5 / (22.553 mm)^2 = 0.11796 kg


def test_planetary_meshes_use_the_planet_inertia():
    """Sun driven, ring fixed: both meshes see the planet alone; W = T_sun / (N r_b,sun)."""
    cfg = load_config("mercury_1a")
    p = cfg.gears["planet"]
    inv_m = p.rb ** 2 / p.mass_properties(cfg.material.rho)[1]
    for pair in cfg.pairs.values():
        law = cfg.contact_law(pair)
        W = 60.0 * 24 / 90 / (3 * cfg.gears["sun"].rb)
        assert f"W = {W:.5g} N" in law.damping_reading
        assert law.zeta == pytest.approx(ratio_from_damping(law.C, W, law.K, law.e, law.d, 1 / inv_m))


def test_damping_and_ratio_are_exclusive():
    with pytest.raises(ConfigError, match="contact.damping .*contact.damping_ratio"):
        loads_config(_spur({"damping": 3000.0, "damping_ratio": 0.05}))
    with pytest.raises(ConfigError, match="contact.damping_ratio"):
        loads_config(_spur({"damping_ratio": -0.05}))


def test_stored_configuration_reproduces_the_ratio_run():
    cfg = loads_config(_spur({"damping_ratio": 0.05}))
    text = resolved_toml(cfg)
    assert "damping_ratio = 0.05" in text and "damping =" not in text
    again = loads_config(text)
    assert again.contact_law(again.pairs["pinion-wheel"]).C == cfg.contact_law(cfg.pairs["pinion-wheel"]).C
