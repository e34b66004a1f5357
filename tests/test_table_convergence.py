"""Convergence of the flexible gears' flank tables in the contact radius (issue 8: converged
means every discretisation, contact tables included).

The compliance of a flank point is tabulated at ``[flexible] table_points`` radii (self term and
mode shapes; linear in the radius between them) and the tables between different flank points
at ``coupling_points`` of them. The force spectrum is the measure: the contact point sweeps the
flank once per tooth pair, so any corner of the interpolated compliance recurs every mesh
period and lands on the mesh harmonics, most visibly above the tenth with light damping. The
flexible spur pair at FE level 1 without shafts and with a 5 % mesh damping ratio is run for 0.2
s from rest; the lines up to 5 kHz over the last 24 mesh periods are compared with a table twice
as fine in both directions (257 radii, coupling on 33).
"""

import numpy as np
import pytest

from flexgear.config import load_config, loads_config
from flexgear.config.loader import preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.full_order import window_metrics
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.errors import ConfigError
from flexgear.reduction.flank import DEFAULT_COUPLING_POINTS, DEFAULT_TABLE_POINTS

MESH_HZ, CYCLES, H = 240.0, 24, 2.5e-5


def config(table_points=None, coupling_points=None):
    cfg = load_config("spur_pair_flexible").use_damping_ratio(0.05)
    cfg.shafts = None
    cfg.flexible["level"] = 1
    if table_points is not None:
        cfg.flexible["table_points"] = table_points
        cfg.flexible["coupling_points"] = coupling_points
    return cfg


def lines(cfg):
    r = simulate(build_model(cfg), 0.2, H, 1, alpha=cfg.simulation["hht_alpha"])
    return window_metrics(r.mesh[:, 0, 0], H, MESH_HZ, CYCLES)["lines"]


@pytest.fixture(scope="module")
def reference():
    return lines(config(257, 33))


def test_default_table_radii_are_the_loader_defaults():
    cfg = config()
    assert cfg.flexible["table_points"] == DEFAULT_TABLE_POINTS == 129
    assert cfg.flexible["coupling_points"] == DEFAULT_COUPLING_POINTS == 17


def test_mesh_lines_are_converged_in_the_table_radii_at_the_defaults(reference):
    """Every line up to 5 kHz at the defaults (129 radii, coupling on 17) within 2 % of the
    twice finer table (the issue's bar for the reduced model), while 17 radii (about the old 16)
    are off by more than 5 %: the check sees what it is for."""
    dev = np.abs(lines(config()) / reference - 1.0)
    coarse = np.abs(lines(config(17, 17)) / reference - 1.0)
    assert dev.max() < 0.02, dev
    assert coarse.max() > 0.05, coarse


@pytest.mark.parametrize("tp, cp", [(129, 18), (129, 130), (65, 1)])
def test_coupling_points_must_divide_the_table(tp, cp):
    doc = preset_path("spur_pair_flexible").read_text()
    doc = doc.replace('formulation = "plane_strain"', f'formulation = "plane_strain"\ntable_points = {tp}\n'
                                                      f'coupling_points = {cp}')
    with pytest.raises(ConfigError, match=r"flexible\.coupling_points"):
        loads_config(doc)
