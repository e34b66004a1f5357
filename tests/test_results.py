"""Tests of flexgear.results: HDF5 round trip, overwrite protection, atomic write."""
import os

import h5py
import numpy as np
import pytest

import flexgear
from flexgear.errors import FlexgearError, ResultExistsError
from flexgear.results.store import (LAYOUT_VERSION, BodySignals, MeshSignals, Result, load, save,
                              validate)

CONFIG = '''# MERCURY 1-A (synthetic test input) - umlaut: ü, degree: °
[gearset]
type = "planetary"
z_sun = 24
z_planet = 21
z_ring = 66

[drive]
input_frequency = 30.0   # Hz
'''


def make_result(n=200, k=3, seed=0) -> Result:
    rng = np.random.default_rng(seed)
    t = 0.1 + np.arange(n) / 5000.0
    meshes = {}
    for name, a, b, kind in [("sun-planet1", "sun", "planet1", "external"),
                             ("planet1-ring", "planet1", "ring", "internal")]:
        tooth_a = rng.integers(-1, 21, size=(n, k))
        meshes[name] = MeshSignals(
            name=name, body_a=a, body_b=b,
            normal_force=rng.normal(236.5, 5.0, n),
            force_global=rng.normal(0.0, 200.0, (n, 2)),
            pair_force=np.abs(rng.normal(0.0, 100.0, (n, k))),
            pair_tooth_a=tooth_a,
            pair_tooth_b=np.where(tooth_a < 0, -1, (tooth_a + 3) % 21),
            pair_side=np.where(tooth_a < 0, 0, rng.choice([-1, 1], (n, k))).astype(np.int8),
            penetration=np.abs(rng.normal(0.0, 1e-6, (n, k))),
            attrs={"z_a": 24 if a == "sun" else 21, "z_b": 21 if b == "planet1" else 66,
                   "kind": kind, "stiffness": 2.38e9, "exponent": 1.3,
                   "contact": {"damping": 3.0e6, "penetration_depth": 3e-4,
                               "law": "impact", "nested": {"flag": True}}})
    bodies = {}
    for name in ("sun", "carrier", "planet1", "ring"):
        bodies[name] = BodySignals(
            name=name, position=rng.normal(0, 1e-3, (n, 2)),
            angle=np.cumsum(rng.normal(0.1, 0.01, n)),
            velocity=rng.normal(0, 1e-2, (n, 2)),
            angular_velocity=rng.normal(188.5, 1.0, n),
            torque=rng.normal(16.0, 0.1, n) if name == "sun" else None,
            attrs={"mass": 0.5, "inertia": 1.2e-4, "z": 24, "role": name, "fixed": name == "ring",
                   "outline_radii": [0.024, 0.026], "tag": None})
    attrs = {"input_frequency": 30.0, "carrier_frequency": 8.0, "mesh_frequency": 528.0,
             "output_rate": 5000.0, "run_in": 0.1, "step": 2e-5,
             "solver": {"n_steps": 55000, "n_newton": 123456, "method": "hht", "alpha": -0.05},
             "flexgear_version": flexgear.__version__, "planets": ("planet1",),
             "phases_deg": np.array([0.0, 120.0, 240.0]), "converged": True}
    return Result(time=t, meshes=meshes, bodies=bodies, config_toml=CONFIG, attrs=attrs)


def assert_same_attrs(a: dict, b: dict, where=""):
    assert set(a) == set(b), where
    for key in a:
        va, vb = a[key], b[key]
        if isinstance(va, dict):
            assert isinstance(vb, dict), f"{where}.{key}"
            assert_same_attrs(va, vb, f"{where}.{key}")
        elif isinstance(va, np.ndarray):
            assert isinstance(vb, np.ndarray) and vb.dtype == va.dtype, f"{where}.{key}"
            np.testing.assert_array_equal(va, vb)
        else:
            assert type(va) is type(vb) and va == vb, f"{where}.{key}: {va!r} != {vb!r}"


def assert_same_array(a, b):
    assert a.dtype == b.dtype and a.shape == b.shape
    np.testing.assert_array_equal(a, b)


def assert_same_result(r: Result, q: Result):
    assert_same_array(r.time, q.time)
    assert q.config_toml == r.config_toml
    assert_same_attrs(r.attrs, q.attrs, "root")
    assert list(q.meshes) == list(r.meshes) and list(q.bodies) == list(r.bodies)
    for name, m in r.meshes.items():
        p = q.meshes[name]
        assert (p.name, p.body_a, p.body_b) == (m.name, m.body_a, m.body_b)
        for f in ("normal_force", "force_global", "pair_force", "pair_tooth_a", "pair_tooth_b",
                  "pair_side", "penetration"):
            assert_same_array(getattr(m, f), getattr(p, f))
        assert_same_attrs(m.attrs, p.attrs, name)
    for name, b in r.bodies.items():
        c = q.bodies[name]
        assert c.name == b.name
        for f in ("position", "angle", "velocity", "angular_velocity"):
            assert_same_array(getattr(b, f), getattr(c, f))
        if b.torque is None:
            assert c.torque is None
        else:
            assert_same_array(b.torque, c.torque)
        assert_same_attrs(b.attrs, c.attrs, name)


def test_round_trip(tmp_path):
    r = make_result()
    path = save(r, tmp_path / "results.h5")
    assert path == tmp_path / "results.h5"
    assert_same_result(r, load(path))
    assert_same_result(r, flexgear.load(str(path)))


def test_round_trip_large_compressed(tmp_path):
    r = make_result(n=5000, k=4)  # above the compression threshold
    save(r, tmp_path / "big.h5")
    assert_same_result(r, load(tmp_path / "big.h5"))


def test_fs():
    assert make_result().fs == pytest.approx(5000.0, rel=1e-12)
    r = make_result()
    r.time = r.time[:1]
    with pytest.raises(ValueError, match="at least 2 samples"):
        r.fs


def test_layout_is_plain_and_documented(tmp_path):
    r = make_result()
    save(r, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "r") as h5:
        assert h5.attrs["layout_version"] == LAYOUT_VERSION
        assert h5.attrs["config_toml"] == CONFIG
        assert h5["time"].attrs["units"] == "s"
        seen = []

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                seen.append(name)
                assert obj.dtype.kind in "iuf", name  # plain numeric, no compound/object
                assert obj.attrs["units"] and obj.attrs["description"], name
        h5.visititems(visit)
        assert "meshes/planet1-ring/force_global" in seen
        assert "bodies/sun/torque" in seen and "bodies/carrier/torque" not in seen
        assert h5["meshes/planet1-ring/force_global"].shape == (200, 2)
        assert h5["meshes/planet1-ring/force_global"].attrs["units"] == "N"
        assert "planet1" in h5["meshes/planet1-ring/force_global"].attrs["description"]
        assert h5["bodies/planet1/angular_velocity"].attrs["units"] == "rad/s"
        assert h5["meshes/planet1-ring"].attrs["body_b"] == "ring"
        assert h5["meshes/planet1-ring"].attrs["contact.law"] == "impact"
        assert h5.attrs["mesh_frequency"] == 528.0


def test_overwrite_refused_and_file_untouched(tmp_path):
    path = tmp_path / "results.h5"
    path.write_bytes(b"previous result")
    before = os.stat(path).st_mtime_ns
    with pytest.raises(ResultExistsError) as err:
        save(make_result(), path)
    msg = str(err.value)
    assert str(path) in msg and "overwrite=True" in msg
    assert isinstance(err.value, FileExistsError)
    assert path.read_bytes() == b"previous result"
    assert os.stat(path).st_mtime_ns == before
    assert sorted(os.listdir(tmp_path)) == ["results.h5"]


def test_overwrite_allowed(tmp_path):
    path = tmp_path / "results.h5"
    save(make_result(seed=1), path)
    r = make_result(seed=2)
    save(r, path, overwrite=True)
    assert_same_result(r, load(path))
    assert sorted(os.listdir(tmp_path)) == ["results.h5"]


def test_atomic_write_leaves_no_temp_file(tmp_path, monkeypatch):
    save(make_result(), tmp_path / "ok.h5")
    assert sorted(os.listdir(tmp_path)) == ["ok.h5"]
    # a failure while writing leaves neither a partial target nor a temporary file
    r = make_result()
    r.attrs["bad"] = object()
    with pytest.raises(ValueError, match="bad"):
        save(r, tmp_path / "failed.h5")
    assert sorted(os.listdir(tmp_path)) == ["ok.h5"]
    # the target only appears by the final rename
    calls = []
    real_link = os.link

    def spy_link(src, dst, *a, **kw):
        calls.append((os.path.basename(src), os.path.basename(dst), os.path.exists(dst)))
        return real_link(src, dst, *a, **kw)
    monkeypatch.setattr(os, "link", spy_link)
    save(make_result(), tmp_path / "new.h5")
    (src, dst, existed), = calls
    assert dst == "new.h5" and not existed and src.startswith(".new.h5.")
    assert sorted(os.listdir(tmp_path)) == ["new.h5", "ok.h5"]


def test_validate_shapes():
    r = make_result()
    r.meshes["sun-planet1"].force_global = np.zeros((200, 3))
    with pytest.raises(ValueError, match=r"sun-planet1.*force_global.*\(200, 2\)"):
        validate(r)
    r = make_result()
    r.meshes["bad/name"] = r.meshes.pop("sun-planet1")
    r.meshes["bad/name"].name = "bad/name"
    with pytest.raises(ValueError, match="without '/'"):
        validate(r)


def test_reserved_attr_rejected(tmp_path):
    r = make_result()
    r.attrs["config_toml"] = "x"
    with pytest.raises(ValueError, match="reserved"):
        save(r, tmp_path / "r.h5")
    assert not os.listdir(tmp_path)


def test_load_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.h5"):
        load(tmp_path / "missing.h5")
    with h5py.File(tmp_path / "other.h5", "w") as h5:
        h5["x"] = 1.0
    with pytest.raises(FlexgearError, match="not a flexgear result"):
        load(tmp_path / "other.h5")
    save(make_result(), tmp_path / "future.h5")
    with h5py.File(tmp_path / "future.h5", "r+") as h5:
        h5.attrs["layout_version"] = LAYOUT_VERSION + 1
    with pytest.raises(FlexgearError, match="layout_version"):
        load(tmp_path / "future.h5")


def test_unreadable_files_are_named_with_what_is_wrong(tmp_path):
    """A directory, a file that is not HDF5 and a truncated result: a FlexgearError naming the
    path and the fault, never h5py's raw OSError."""
    (tmp_path / "run").mkdir()
    save(make_result(), tmp_path / "run" / "results.h5")
    with pytest.raises(FlexgearError) as err:
        flexgear.load(tmp_path / "run")
    assert str(tmp_path / "run") in str(err.value) and "is a directory" in str(err.value)
    assert "results.h5" in str(err.value)  # what to give instead
    (tmp_path / "notes.txt").write_text("not a result\n")
    with pytest.raises(FlexgearError, match=r"notes\.txt' is not an HDF5 file"):
        flexgear.load(tmp_path / "notes.txt")
    data = (tmp_path / "run" / "results.h5").read_bytes()
    (tmp_path / "cut.h5").write_bytes(data[:len(data) // 2])
    with pytest.raises(FlexgearError, match=rf"cut\.h5' is truncated: {len(data) // 2} bytes of the {len(data)}"):
        flexgear.load(tmp_path / "cut.h5")


def test_condensed_coordinates_round_trip_and_older_layouts(tmp_path):
    """Layout 4: a flexible body's condensed modal coordinates (n, nq) are stored as a dataset
    with units and description, their frequencies as the body attribute
    ``condensed_frequencies``; a file of an older layout (no such dataset) reads back with
    ``condensed_coordinates = None``; a wrong shape is refused naming the field."""
    assert LAYOUT_VERSION >= 4
    r = make_result()
    eta = np.random.default_rng(1).normal(0.0, 1e-6, (200, 7))
    r.bodies["sun"].condensed_coordinates = eta
    r.bodies["sun"].attrs["condensed_frequencies"] = [31e3 + 1e3 * k for k in range(7)]
    save(r, tmp_path / "r.h5")
    back = load(tmp_path / "r.h5")
    assert_same_array(back.bodies["sun"].condensed_coordinates, eta)
    assert back.bodies["sun"].attrs["condensed_frequencies"] == r.bodies["sun"].attrs["condensed_frequencies"]
    assert back.bodies["planet1"].condensed_coordinates is None
    with h5py.File(tmp_path / "r.h5", "r+") as h5:
        ds = h5["bodies/sun/condensed_coordinates"]
        assert ds.attrs["units"] == "sqrt(kg) m" and "condensed" in ds.attrs["description"]
        del h5["bodies/sun/condensed_coordinates"]  # as a layout 3 file
        h5.attrs["layout_version"] = 3
    assert load(tmp_path / "r.h5").bodies["sun"].condensed_coordinates is None
    r.bodies["sun"].condensed_coordinates = eta[:-1]
    with pytest.raises(ValueError, match=r"sun.*condensed_coordinates.*\(200, \*\)"):
        validate(r)


def test_sensors_round_trip_and_older_layouts(tmp_path):
    """Layout 5: ``/sensors/<name>/<path model>`` datasets with units, description and the path
    model's parameters as attributes, the sensor's definition on the group; they read back bit
    for bit, in order (monitor analyses the first); a layout 4 file reads with no sensors; a
    signal of the wrong length or without units is refused naming it."""
    from flexgear.gears.housing import Sensor
    from flexgear.results.store import SensorSignals

    assert LAYOUT_VERSION >= 5
    r = make_result()
    s = Sensor("top", "housing", (0.0, 0.089), (0.0, 1.0), angle_deg=90.0)
    y = np.random.default_rng(2).normal(size=(2, 200))
    r.sensors["top"] = SensorSignals("top", s.definition(), {"housing_path": y[0], "planet_pass": y[1]},
                                     {"housing_path": {"units": "m/s^2", "description": "a", "damping_ratio": 0.02,
                                                       "channels": ["sun.x", "ring.moment"]},
                                      "planet_pass": {"units": "N", "description": "b", "window": "hann"}})
    save(r, tmp_path / "r.h5")
    back = load(tmp_path / "r.h5")
    got = back.sensors["top"]
    assert list(got.signals) == ["housing_path", "planet_pass"]
    assert_same_array(got.signals["housing_path"], y[0]) and got.signal_attrs == r.sensors["top"].signal_attrs
    assert got.attrs == s.definition()
    with h5py.File(tmp_path / "r.h5", "r+") as h5:
        assert h5["sensors/top/planet_pass"].attrs["units"] == "N"
        del h5["sensors"]  # as a layout 4 file
        h5.attrs["layout_version"] = 4
    assert load(tmp_path / "r.h5").sensors == {}
    r.sensors["top"].signals["planet_pass"] = y[1, :-1]
    with pytest.raises(ValueError, match=r"sensors\['top'\].signals\['planet_pass'\]: expected shape \(200\), got \(199,\)"):
        validate(r)
    r.sensors["top"].signals["planet_pass"] = y[1]
    r.housing_loads["ring.moment"] = y[0, :-2]
    with pytest.raises(ValueError, match=r"housing_loads\['ring.moment'\]: expected shape \(200\)"):
        validate(r)
    r.housing_loads["ring.moment"] = y[0]
    save(r, tmp_path / "loads.h5")
    with h5py.File(tmp_path / "loads.h5", "r") as h5:
        assert h5["housing_loads/ring.moment"].attrs["units"] == "N m"
    assert_same_array(load(tmp_path / "loads.h5").housing_loads["ring.moment"], y[0])
    del r.sensors["top"].signal_attrs["planet_pass"]["units"]
    with pytest.raises(ValueError, match=r"signal_attrs\['planet_pass'\]: needs 'units'"):
        validate(r)
