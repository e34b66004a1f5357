"""On-disk cache of the gears' signed distance fields (the most of a rigid model's build time)."""
import numpy as np
import pytest

import flexgear.gears.sdf as contact
from flexgear.gears.sdf import build_sdf, gear_sdf, sdf_cache_dir, sdf_cache_key
from flexgear.gears.geometry import SpurGear

M = 2e-3
COARSE = M / 40  # a coarse grid keeps the test fast


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXGEAR_CACHE_DIR", str(tmp_path))
    gear_sdf.cache_clear()
    yield sdf_cache_dir()
    gear_sdf.cache_clear()


def _no_build(*args, **kw):
    raise AssertionError("the field was rebuilt, not loaded from the cache")


def test_a_cached_field_is_the_built_one_bit_for_bit(cache, monkeypatch):
    g = SpurGear(21, M, bore_diameter=0.02, name="planet")
    first = gear_sdf(g, COARSE)
    assert len(list(cache.glob("sdf-*.npz"))) == 1
    gear_sdf.cache_clear()
    with monkeypatch.context() as mp:
        mp.setattr(contact, "cKDTree", _no_build)  # what building a field needs first
        again = gear_sdf(g, COARSE)
    ref = build_sdf(g, COARSE)
    for s in (first, again):
        assert np.array_equal(s.grid, ref.grid)
        assert (s.r0, s.dr, s.phi0, s.dphi, s.pitch, s.internal, s.z) == \
               (ref.r0, ref.dr, ref.phi0, ref.dphi, ref.pitch, ref.internal, ref.z)


def test_a_corrupt_entry_is_rebuilt(cache):
    g = SpurGear(66, M, internal=True, rim_diameter=0.16, ha=0.85, name="ring")
    gear_sdf(g, COARSE)
    npz = next(cache.glob("sdf-*.npz"))
    npz.write_bytes(npz.read_bytes()[:-100])
    gear_sdf.cache_clear()
    assert np.array_equal(gear_sdf(g, COARSE).grid, build_sdf(g, COARSE).grid)


def test_the_key_follows_geometry_and_resolution():
    g = SpurGear(24, M, bore_diameter=0.02, name="sun")
    k0 = sdf_cache_key(g, COARSE)[0]
    assert sdf_cache_key(SpurGear(24, M, bore_diameter=0.02, name="other name"), COARSE)[0] == k0
    assert sdf_cache_key(g, COARSE / 2)[0] != k0
    assert sdf_cache_key(SpurGear(24, M, bore_diameter=0.02, thinning=1e-5), COARSE)[0] != k0
    assert sdf_cache_key(SpurGear(25, M, bore_diameter=0.02), COARSE)[0] != k0
