"""The warm start of the full contact search (flexgear.dynamics.contact._scan, local = False): a
half tooth the previous full search cached is walked downhill from its cached sample instead of
scanned coarsely and refined. Along real trajectories of the rigid spur pair and MERCURY 1-A and
of the flexible spur pair (near contacts reported, gap > 0), the search pattern of a run (a full
search every FULL_SEARCH_EVERY-th step, local searches between) is replayed at the recorded body
poses; at every full search the warm search (the cache as the local searches left it) must give
the cold one's results (``ncache = 0``: every half tooth scanned) bit for bit: the contacts
(depth, point, normal, tooth pair, side) and the cache rows the local searches continue from.

The equality holds whenever the signed distance along each cached half tooth has one local
minimum (see the comment above ``_scan``); a second minimum apart from the walk's that is not
caught by its guards would show here as a difference."""
import numpy as np
import pytest

from flexgear.config import load_config
from flexgear.dynamics.assembly import build_model
from flexgear.dynamics.contact import MAX_CONTACTS, mesh_contacts
from flexgear.dynamics.solver import COARSE_STRIDE, FULL_SEARCH_EVERY, simulate

# preset: simulated time [s] (a full search every 8 steps: 50 full searches of each mesh in 400 steps)
RUNS = {"spur_pair": 0.01, "mercury_1a": 0.01, "spur_pair_flexible": 0.0025}


def _poses(preset):
    """The model, its packed meshes and the body poses (nsteps, nb, 3) of a short run."""
    cfg = load_config(preset)
    model = build_model(cfg)
    h = cfg.simulation["step"]
    rec = simulate(model, RUNS[preset], h, 8).records
    return model, model.pack(COARSE_STRIDE).meshes, np.stack([rec.x, rec.y, rec.theta], axis=-1)


def _search(model, meshes, m, pose, local, cache, ncache):
    a, b = meshes.body_a[m], meshes.body_b[m]
    out_f = np.full((MAX_CONTACTS, 5), np.nan)
    out_i = np.full((MAX_CONTACTS, 3), -9, np.int64)
    n = mesh_contacts(pose[a], pose[b], meshes.gear_a[m], meshes.gear_b[m], meshes.internal[m], model.tables,
                      meshes.ncand_a[m], meshes.ncand_b[m], meshes.stride[m], out_f, out_i, local, cache, ncache,
                      meshes.gap[m])
    return n, out_f[:n], out_i[:n], cache[:ncache[0]].copy()


@pytest.mark.parametrize("preset", sorted(RUNS))
def test_warm_full_search_equals_the_cold_one_along_a_run(preset):
    model, meshes, P = _poses(preset)
    nm = meshes.body_a.shape[0]
    cache = np.zeros((nm, 4 * MAX_CONTACTS, 4), np.int64)
    ncache = np.zeros((nm, 1), np.int64)
    warm_searches = contacts = near = 0
    for k in range(P.shape[0]):
        for m in range(nm):
            if k % FULL_SEARCH_EVERY:
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
    full = nm * len(range(0, P.shape[0], FULL_SEARCH_EVERY))
    assert warm_searches >= full - nm
    assert contacts >= full and near > contacts
