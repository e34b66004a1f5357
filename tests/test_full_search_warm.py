"""The warm start of the full contact search (flexgear.dynamics.contact.search._scan, local = False): a
half tooth the previous full search cached is walked downhill from its cached sample instead of
scanned coarsely and refined. Along real trajectories of the rigid spur pair and MERCURY 1-A and
of the flexible spur pair (near contacts reported, gap > 0), the search pattern of a run (a full
search every ``full_search_every(h)``-th step, local searches between) is replayed at the recorded body
poses; at every full search the warm search (the cache as the local searches left it) must give
the cold one's results (``ncache = 0``: every half tooth scanned) bit for bit: the contacts
(depth, point, normal, tooth pair, side) and the cache rows the local searches continue from.

The equality holds whenever the signed distance along each cached half tooth has one local
minimum (see the comment above ``_scan``); a second minimum apart from the walk's that is not
caught by its guards would show here as a difference."""
import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.contact.search import MAX_CONTACTS, MeshPair, mesh_contacts
from flexgear.dynamics.integrator.simulation import COARSE_STRIDE, FULL_SEARCH_INTERVAL, full_search_every, simulate

# preset: simulated time [s] (a full search every 200 us: 50 full searches of each mesh in 0.01 s)
RUNS = {"spur_pair": 0.01, "mercury_1a": 0.01, "spur_pair_flexible": 0.01}


def _poses(preset):
    """The model, its packed meshes, the body poses (nsteps, nb, 3) of a short run and its steps
    between two full searches."""
    cfg = load_config(preset)
    model = build_model(cfg)
    h = cfg.simulation["step"]
    rec = simulate(model, RUNS[preset], h, 8).records
    return model, model.pack(COARSE_STRIDE).meshes, np.stack([rec.x, rec.y, rec.theta], axis=-1), full_search_every(h)


def _search(model, meshes, m, pose, local, cache, ncache):
    a, b = meshes.body_a[m], meshes.body_b[m]
    out_f = np.full((MAX_CONTACTS, 5), np.nan)
    out_i = np.full((MAX_CONTACTS, 3), -9, np.int64)
    pair = MeshPair(meshes.gear_a[m], meshes.gear_b[m], meshes.internal[m], meshes.ncand_a[m], meshes.ncand_b[m],
                    meshes.stride[m], meshes.gap[m])
    n = mesh_contacts(pose[a], pose[b], pair, model.tables, out_f, out_i, local, cache, ncache)
    return n, out_f[:n], out_i[:n], cache[:ncache[0]].copy()


@pytest.mark.parametrize("preset", sorted(RUNS))
def test_warm_full_search_equals_the_cold_one_along_a_run(preset):
    model, meshes, P, every = _poses(preset)
    nm = meshes.body_a.shape[0]
    cache = np.zeros((nm, 4 * MAX_CONTACTS, 4), np.int64)
    ncache = np.zeros((nm, 1), np.int64)
    warm_searches = contacts = near = 0
    for k in range(P.shape[0]):
        for m in range(nm):
            if k % every:
                _search(model, meshes, m, P[k], True, cache[m], ncache[m])
                continue
            cold = _search(model, meshes, m, P[k], False, cache[m].copy(), np.zeros(1, np.int64))
            warm_searches += ncache[m, 0] > 0
            warm = _search(model, meshes, m, P[k], False, cache[m], ncache[m])
            assert warm[0] == cold[0], (k, m)
            assert np.array_equal(warm[1], cold[1]), (k, m)  # depth, point, normal: bit for bit
            assert np.array_equal(warm[2], cold[2]), (k, m)  # tooth pair and side
            assert np.array_equal(warm[3], cold[3]), (k, m)  # the half teeth followed until the next one
            contacts += warm[0]
            near += len(warm[3])
    # the warm start was exercised: nearly every full search had cached half teeth, in contact
    full = nm * len(range(0, P.shape[0], every))
    assert warm_searches >= full - nm
    assert contacts >= full and near > contacts


def test_full_search_interval_is_one_of_simulated_time():
    """A full search every 200 us of simulated time: 8 steps at the rigid presets' 25 us (as
    before), 32 at the flexible presets' 6.25 us; a count below one step is refused."""
    assert full_search_every(2.5e-5) == 8
    assert full_search_every(6.25e-6) == 32
    for h in (1e-4, 2.5e-5, 1e-5, 6.25e-6, 1.5625e-6):
        assert abs(full_search_every(h) * h - FULL_SEARCH_INTERVAL) <= 0.5 * h
    model = build_model(load_config("spur_pair"))
    with pytest.raises(ValueError, match="full_every = 0"):
        simulate(model, 1e-3, 2.5e-5, 8, full_every=0)


@pytest.mark.parametrize("preset", ["spur_pair_flexible", pytest.param("mercury_1a_flexible", marks=pytest.mark.slow)])
def test_full_search_every_200_us_finds_the_contacts_of_every_8_steps(preset):
    """The flexible presets' full search every 200 us (32 steps) against every 8 steps (50 us,
    the interval before it became one of time), 0.12 s from the start (load ramp and run-in):
    the same tooth pairs and flanks at every recorded sample, and mesh forces within 5e-3 of
    their RMS about the mean after the ramp (the records of one-pass steps differ at the
    Newton tolerance: measured 1.7e-3 on the spur pair, 9e-4 on MERCURY 1-A; a contact found
    late would put a tooth pair's force, a large part of the mean, into the difference)."""
    cfg = load_config(preset)
    model = build_model(cfg)
    h = cfg.simulation["step"]
    assert full_search_every(h) == 32
    every8 = simulate(model, 0.12, h, 8, full_every=8)
    every200us = simulate(model, 0.12, h, 8)
    assert np.array_equal(every8.pair_i, every200us.pair_i)
    i0 = int(round(0.06 / h))
    a, b = every8.mesh[i0:, :, 0], every200us.mesh[i0:, :, 0]
    rms = np.sqrt(np.mean((a - a.mean(axis=0)) ** 2, axis=0))
    assert np.all(np.abs(a - b).max(axis=0) < 5e-3 * rms)
