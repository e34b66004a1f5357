"""Loaded mesh with contact outside the path of contact (``loaded_mesh(..., extended=True)``).

Independent references: the no-load separation of a tip corner from the mate's flank against a
direct computation on the generated tooth outlines (polygons of ``SpurGear.tooth_outline``,
gear 2 turned until they touch); at a load too small to close any gap the extended analysis
against the path-only one; the static solution against its own equations (equilibrium,
compatibility, complementarity). The comparison with the slowly turned flexible pair is in
tests/test_flexible.py.
"""
import math

import numpy as np
import pytest
from matplotlib.path import Path
from scipy.optimize import brentq

from flexgear.config import load_config
from flexgear.errors import ConfigError
from flexgear.fe.meshing import MeshSettings
from flexgear.stiffness.compliance import tooth_fe_model, tooth_step
from flexgear.stiffness.hertz import hertz_approach
from flexgear.stiffness.loaded_mesh import (ON_PATH, TIP1, TIP2, _pair_compliance, extended_grid,
                                            loaded_mesh, tip_separation, usable_path)


@pytest.fixture(scope="module")
def cfg():
    return load_config("mercury_1a")


# ------------------------------------------------------------------ outline geometry
def _turn(pts, th, centre=(0.0, 0.0)):
    c, s = math.cos(th), math.sin(th)
    return pts @ np.array([[c, s], [-s, c]]) + np.asarray(centre)


def _tooth_polygon(g, ds):
    """Tooth 0 as a closed polygon around its material (through the centre, or the rim of a ring)."""
    o = g.tooth_outline(ds).points
    if g.internal:
        R = g.rim_diameter / 2
        a0, a1 = math.atan2(o[0, 1], o[0, 0]), math.atan2(o[-1, 1], o[-1, 0])
        return np.vstack([o, R * np.array([[math.cos(a1), math.sin(a1)], [math.cos(a0), math.sin(a0)]])])
    return np.vstack([o, [[0.0, 0.0]]])


def _signed_distance(P, A, near):
    """Distance of points P from the edges of polygon A that start at vertices ``near``;
    negative inside A."""
    a = A[near]
    d = np.roll(A, -1, axis=0)[near] - a
    t = np.clip(((P[:, None, :] - a[None]) * d[None]).sum(-1) / (d * d).sum(-1)[None], 0, 1)
    dist = np.sqrt(((P[:, None, :] - a[None] - t[..., None] * d[None]) ** 2).sum(-1)).min(axis=1)
    return np.where(Path(A).contains_points(P), -dist, dist)


def _outline_closing(pair, s_values, ds):
    """Turn of gear 2 (times r_b2, gear 1 held) from its conjugate pose at which the outlines of
    the tooth pair meeting at s first touch. Poses: gear 1 turned by s / r_b1 and gear 2 by
    s / r_b2 (the gear ratio) from the pose where the two outlines touch at s = 0."""
    g1, g2 = pair.g1, pair.g2
    sg = -1.0 if pair.internal else 1.0
    aw = pair.alpha_w
    o2 = np.array([sg * pair.centre_distance, 0.0])
    rw1, rw2 = g1.rb / math.cos(aw), g2.rb / math.cos(aw)
    th1 = -float(g1.involute_half_angle(rw1))  # starting guesses of the poses at s = 0
    th2 = float(g2.involute_half_angle(rw2)) if pair.internal else math.pi - float(g2.involute_half_angle(rw2))
    A0, B0 = _tooth_polygon(g1, ds), _tooth_polygon(g2, ds)
    e = np.array([math.sin(aw), math.cos(aw)])
    T1 = g1.rb * np.array([math.cos(aw), -math.sin(aw)])

    def touch(s, th2_ref):
        A = _turn(A0, th1 + s / g1.rb)
        P = T1 + (g1.rb * math.tan(aw) + s) * e
        na = np.hypot(*(A - P).T) < 1.5 * g1.module

        def f(phi):
            B = _turn(B0, th2_ref - sg * s / g2.rb + sg * phi, o2)
            nb = np.hypot(*(B - P).T) < 1.5 * g1.module
            return min(_signed_distance(A[na], B, nb).min(), _signed_distance(B[nb], A, na).min())
        return g2.rb * brentq(f, -30e-6 / g2.rb, 300e-6 / g2.rb, xtol=1e-14)

    ref = th2 + sg * touch(0.0, th2) / g2.rb
    return np.array([touch(s, ref) for s in s_values])


def test_tip_separation_equals_the_closing_of_the_generated_outlines(cfg):
    """Before and after the path (tip corner of gear 2 / gear 1 against the mate's involute)
    the analytic separation equals the turn that makes the outline polygons touch, within
    0.1 um (measured: < 0.005 um up to 75 um of separation), for an external and an internal
    pair; on the path both are 0."""
    for name in ("sun-planet", "planet-ring"):
        pair = cfg.pairs[name]
        g = extended_grid(pair)
        before, after = np.flatnonzero(g.tip == TIP2), np.flatnonzero(g.tip == TIP1)
        assert len(before) >= 2 and len(after) >= 2, name
        on = np.flatnonzero(g.tip == ON_PATH)
        idx = np.r_[before[0], before[-1], on[[0, -1]], after[0], after[-1]]
        ref = _outline_closing(pair, g.s[idx], pair.g1.module / 100)
        assert np.allclose(g.gap[idx], ref, rtol=0, atol=0.1e-6), (name, g.gap[idx] - ref)
        assert np.all(g.gap[on] == 0) and np.all(g.arm[on] == 1)
        # the separation grows away from the path on both sides
        assert np.all(np.diff(g.gap[before]) < 0) and np.all(np.diff(g.gap[after]) > 0)
        assert g.gap[idx[0]] > 5e-6 and g.gap[idx[-1]] > 2e-6


def test_extended_grid_stays_on_the_involutes_and_within_two_pitches(cfg):
    for pair in cfg.pairs.values():
        g = extended_grid(pair, 24)
        lo, hi, _ = usable_path(pair)
        assert g.s[0] < lo and g.s[-1] > hi
        assert np.allclose(np.diff(g.s), pair.g1.pb / 24)
        assert (len(g.s) - 1) * pair.g1.pb / 24 < 2 * pair.g1.pb  # at most two pairs at a time
        assert np.all((g.r1 >= pair.g1.r_form - 1e-9) & (g.r1 <= pair.g1.ra + 1e-9))
        r2lo, r2hi = sorted((pair.g2.r_form, pair.g2.ra))
        assert np.all((g.r2 >= r2lo - 1e-9) & (g.r2 <= r2hi + 1e-9))
        # a corner: at its tip radius
        assert np.allclose(g.r1[g.tip == TIP1], pair.g1.ra) and np.allclose(g.r2[g.tip == TIP2], pair.g2.ra)
        sep = tip_separation(pair, g.s)
        assert np.all(sep.normal_gap >= 0) and np.all(sep.arm > 0.5)


# ------------------------------------------------------------------ static solution
@pytest.fixture(scope="module")
def spur_models(cfg):
    pair = cfg.pairs["sun-planet"]
    return tuple(tooth_fe_model(g, MeshSettings(level=0), cfg.material)[0] for g in (pair.g1, pair.g2))


@pytest.fixture(scope="module")
def spur_meshes(cfg, spur_models):
    pair = cfg.pairs["sun-planet"]
    kw = dict(material=cfg.material, n_positions=12, models=spur_models)
    F = 200.0 / pair.g2.rb
    return {(load, ext): loaded_mesh(pair, load, extended=ext, **kw)
            for load in (1.0, F) for ext in (False, True)}


def test_extended_mesh_equals_the_path_only_mesh_at_a_small_load(spur_meshes):
    """At 1 N no separation closes: the same transmission error at the same positions (the
    extended grid starts a whole number of steps earlier) and the same pairs in contact."""
    a, b = spur_meshes[(1.0, False)], spur_meshes[(1.0, True)]
    step = a.pair.g1.pb / a.grid.n
    k0 = int(round((a.s[0] - b.s[0]) / step))
    assert k0 > 0 and b.s[0] + k0 * step == pytest.approx(a.s[0], abs=1e-12)
    assert np.allclose(np.roll(b.te, -k0), a.te, rtol=1e-12, atol=0)
    assert np.array_equal(np.roll(b.n_pairs, -k0), a.n_pairs)
    assert b.c_gamma == pytest.approx(a.c_gamma, rel=1e-12)


def test_extended_mesh_solves_its_contact_problem(cfg, spur_meshes):
    """At 200 N m: equilibrium sum arm_k F_k = F, compatibility on the loaded pairs,
    complementarity on the open ones (no rigid overlap left unloaded), from the FE tables."""
    ms = spur_meshes[(200.0 / cfg.pairs["sun-planet"].g2.rb, True)]
    g, n, J = ms.grid, ms.grid.n, len(ms.grid.s)
    L = ms.face_width

    sig1, sig2 = tooth_step(ms.pair.g1), -tooth_step(ms.pair.g2)
    outside = 0
    for k in range(len(ms.s)):
        idx = list(range(k, J, n))
        Fk = ms.pair_loads[k, :len(idx)]
        assert g.arm[idx] @ Fk == pytest.approx(ms.load, rel=1e-9)
        C = _pair_compliance(ms.c1, ms.c2, idx, sig1, sig2)
        free = g.arm[idx] * (ms.te[k] - g.gap[idx]) - C @ Fk
        for i, j in enumerate(idx):
            if Fk[i] > 0:
                h = hertz_approach(Fk[i], g.R[j], L, cfg.material, cfg.material, ms.c1.depth,
                                   ms.c2.depth, "plane_strain")
                assert free[i] == pytest.approx(h, rel=1e-8)
                outside += g.tip[j] != ON_PATH
            else:
                assert free[i] <= 1e-12
    assert outside > 0  # some pairs outside the path carry load
    # contact outside the path: more two-pair positions and a lower transmission error
    a = spur_meshes[(ms.load, False)]
    assert np.mean(ms.n_pairs == 2) > np.mean(a.n_pairs == 2) + 1.5 / len(ms.s)
    assert ms.te.mean() < a.te.mean()
    assert ms.te.max() <= a.te.max() * (1 + 1e-9)


def test_extended_mesh_rejects_a_too_short_extension(cfg, spur_models):
    pair = cfg.pairs["sun-planet"]
    with pytest.raises(ConfigError, match="max_gap"):  # 4 um: not one grid step (16 um)
        extended_grid(pair, 12, max_gap=0.002)
    with pytest.raises(ConfigError, match="max_gap"):
        extended_grid(pair, 12, max_gap=0.0)
    with pytest.raises(ConfigError, match="max_gap"):  # 16 um: one step, loaded at 200 N m
        loaded_mesh(pair, 200.0 / pair.g2.rb, material=cfg.material, n_positions=12, extended=True,
                    max_gap=0.01, models=spur_models)
