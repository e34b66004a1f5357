"""The fault's tooth and flank numbers are those of the dynamics: the tooth whose flank the rigid
engagement geometry (flexgear.gears.kinematics) puts on the path of contact is the tooth the
contact search reports (flexgear.dynamics.contact.search) and the results record (pair_tooth_a/b,
pair_side), and the loaded flank flexgear.config.faults.loaded_flanks names is the one loaded in a
simulation."""
import math
import warnings

import numpy as np
import pytest

from flexgear.config import load_config, loads_config
from flexgear.config.faults import loaded_flanks, mesh_pairs
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.contact.search import MAX_CONTACTS, MeshPair, mesh_contacts
from flexgear.gears.faults import LEFT, RIGHT
from flexgear.gears.kinematics import contact_roll_range, flank_roll_angle, line_of_action, mate_flank

MARGIN = 0.03  # rad of roll angle at zero load: corner contact at the ends of the path
LOADED = 0.06  # rad under the presets' load (about 70 um of approach): contact starts early, ends late


def paired(pair, poses, xa, xb):
    """Miss [m] of the roll lengths of a contacting pair from the line of action: r_b1 xi_1 + r_b2 xi_2
    (external) or r_b2 xi_2 - r_b1 xi_1 (internal) equals a sin(alpha_w) when both flanks touch
    the same point of it; a pairing one tooth off misses by a base pitch."""
    a = math.hypot(poses[1][0] - poses[0][0], poses[1][1] - poses[0][1])
    sin_aw = math.sqrt(1 - ((pair.g2.rb - pair.g1.rb if pair.internal else pair.g1.rb + pair.g2.rb) / a) ** 2)
    la, lb = pair.g1.rb * xa, pair.g2.rb * xb
    return abs((lb - la if pair.internal else la + lb) - a * sin_aw)


def search(model, mesh, poses):
    out_f = np.zeros((MAX_CONTACTS, 5))
    out_i = np.zeros((MAX_CONTACTS, 3), np.int64)
    a, b = model.bodies[mesh.a], model.bodies[mesh.b]
    pair = MeshPair(a.gear, b.gear, mesh.internal, mesh.ncand_a, mesh.ncand_b, 16, 0.0)
    n = mesh_contacts(np.asarray(poses[0], float), np.asarray(poses[1], float), pair, model.tables, out_f, out_i)
    return out_i[:n].copy()


def predicted(pair, poses, side_a):
    """Roll angles of every tooth's flank of both gears on the line of action that loads side_a."""
    (xa, ya, tha), (xb, yb, thb) = poses
    beta = math.atan2(yb - ya, xb - xa) if not pair.internal else math.atan2(ya - yb, xa - xb)
    ga, gb = line_of_action(pair, beta, side_a)
    side_b = mate_flank(side_a, pair.internal)
    xi_a = flank_roll_angle(pair.g1, np.arange(pair.g1.z), side_a, tha, ga)
    xi_b = flank_roll_angle(pair.g2, np.arange(pair.g2.z), side_b, thb, gb)
    return xi_a, xi_b


def within(xi, rng, margin):
    return (xi >= rng[0] - margin) & (xi <= rng[1] + margin)


@pytest.mark.parametrize("preset,mesh_name", [("spur_pair", "pinion-wheel"), ("mercury_1a", "sun-planet1"),
                                              ("mercury_1a", "planet2-ring")])
@pytest.mark.parametrize("turn", [1, -1])
def test_contact_search_reports_the_teeth_the_geometry_puts_in_mesh(preset, mesh_name, turn):
    """At the assembled (zero-load) poses carried through two mesh cycles, gear a turned by a small
    angle counter-clockwise (turn = +1) closes its left flanks, clockwise its right ones; the
    reported teeth are those whose flanks lie on the path of contact."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = load_config(preset)
        model = build_model(cfg)
    mesh = next(m for m in model.meshes if m.name == mesh_name)
    _, _, pair = mesh_pairs(cfg)[mesh_name]
    A, B = model.bodies[mesh.a], model.bodies[mesh.b]
    pa, pb = np.asarray(A.pin, float), np.asarray(B.pin, float)  # carrier at angle 0: pins are global
    ratio = (-1 if not pair.internal else 1) * pair.g1.z / pair.g2.z
    ra, rb = contact_roll_range(pair)
    side = LEFT if turn > 0 else RIGHT
    nominal = 0
    for phi in np.linspace(0.0, 2 * pair.g1.pitch_angle, 41):
        poses = ((pa[0], pa[1], A.theta0 + phi + turn * 2e-4), (pb[0], pb[1], B.theta0 + ratio * phi))
        found = search(model, mesh, poses)
        assert len(found) and np.all(found[:, 2] == side)
        xi_a, xi_b = predicted(pair, poses, side)
        for ta, tb, _ in found:
            assert within(xi_a[ta], ra, MARGIN) and within(xi_b[tb], rb, MARGIN)
            assert paired(pair, poses, xi_a[ta], xi_b[tb]) < 0.05 * pair.g1.pb
        inner_a = set(np.nonzero(within(xi_a, ra, -MARGIN))[0])
        inner_b = set(np.nonzero(within(xi_b, rb, -MARGIN))[0])
        assert inner_a <= set(found[:, 0]) and inner_b <= set(found[:, 1])
        nominal += len(inner_a)
    assert nominal > 41  # the path holds more than one pair for part of the cycle


@pytest.mark.parametrize("fixture", ["spur_result", "planetary_result"])
def test_results_number_teeth_and_flanks_as_the_faults(fixture, request):
    """In a loaded rigid run, every loaded tooth-pair slot holds the tooth whose loaded flank the
    engagement geometry puts on the path of contact at the recorded body angles, on the flank
    loaded_flanks names."""
    res = request.getfixturevalue(fixture)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cfg = loads_config(res.config_toml)
    flanks = loaded_flanks(cfg)
    checked = 0
    for name, (a, b, pair) in mesh_pairs(cfg).items():
        m = res.meshes[name]
        A, B = res.bodies[a], res.bodies[b]
        ra, rb = contact_roll_range(pair)
        side_a = flanks[name][0]
        big = m.pair_force > 0.05 * m.pair_force.max()
        rows = np.nonzero(big.any(axis=1))[0][::7]
        for i in rows:
            poses = ((*A.position[i], A.angle[i]), (*B.position[i], B.angle[i]))
            xi_a, xi_b = predicted(pair, poses, side_a)
            for s in np.nonzero(big[i])[0]:
                ta, tb = m.pair_tooth_a[i, s], m.pair_tooth_b[i, s]
                assert m.pair_side[i, s] == side_a
                assert within(xi_a[ta], ra, LOADED) and within(xi_b[tb], rb, LOADED)
                assert paired(pair, poses, xi_a[ta], xi_b[tb]) < 0.1 * pair.g1.pb
                checked += 1
    assert checked > 200
