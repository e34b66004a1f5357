"""One flexible gear, end to end and cached: mesh -> FE model -> Craig-Bampton body -> flank data.

:func:`reduce_gear` returns a :class:`GearReduction`: ``body``
(:class:`~flexgear.reduction.body.ReducedBody`, coordinates ``[u_x, u_y, theta, eta_1..eta_n]``),
``tables`` (:class:`~flexgear.reduction.flank.FlankTables`) and ``modal`` (z, 2, J, n): the
normal flank displacement per unit coordinate at the table radii of every tooth (sides
``flank.SIDES`` = left, right).

Default cutoff :data:`DEFAULT_CUTOFF` (100 kHz): modes far above what the step resolves answer
quasi-statically, which the residual flexibility carries exactly, so the cutoff only has to lie
above every gear's first clamped mode with a margin; many more modes would let them carry part
of the contact's local deformation and turn the residual self compliance negative.

Cache: ``<cache_dir>/reduction-<sha256>.npz`` (reduced matrices, flank tables), the basis in
``.basis.npy`` and a ``.json`` sidecar with the key and both files' SHA-256. The key holds the
mesh digest (:mod:`flexgear.fe.meshing`), material, thickness, formulation, support, cutoff,
table settings, :data:`FORMAT_VERSION`, eigen-solver tolerances and numpy/scipy/scikit-fem
versions; a missing, corrupt or stale entry is rebuilt, never used. A cached gear assembles K,
M and reads the basis only on first use (``reconstruct``, contact loads, stresses). See the
theory page *Reduction and residual tables*, section *Cutoff and caching*.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..files import atomic_write_arrays, atomic_write_json, discard_files, entry_lock, sha256_file
from ..fe.elasticity import EIGEN_RESIDUAL_TOL, FORMULATIONS, LANCZOS_TOL, assemble, single_threaded_blas
from ..fe.crack import cracked_mesh_digest, mesh_cracked_gear, root_crack
from ..fe.meshing import USER_CACHE, MeshSettings, check_meshable, mesh_digest, mesh_gear
from ..gears.faults import fault_record
from ..gears.material import Material
from ..gears.modified import OUTLINE_FAULTS, FaultyGear, faulty_teeth
from ..stiffness.compliance import DEFAULT_DEPTH, DEFAULT_SPREAD, MIN_SPREAD
from .body import LazyBasisBody, ReducedBody
from .flank import (DEFAULT_COUPLING_POINTS, DEFAULT_TABLE_POINTS, SIDES, FlankTables, coupling_stride,
                    flank_samples, flank_tables, modal_table, reference_tooth, table_radii)
from .interface import DEFAULT_BOLTS, RING_SUPPORTS, InterfaceMap, gear_interface
from .reductor import ClampedFactorisation, CraigBamptonReductor
from .residual import ResidualFlexibility

log = logging.getLogger(__name__)

#: Bump when the cached content or the reduction method changes (invalidates old entries).
FORMAT_VERSION = 5  # 2: residual tables for every tooth distance and both pairs of flank sides; 4: 129 table
#                     radii, the coupling tables on 17 of them; 5: the basis in its own .npy, read on first use
#: Default fixed-interface mode cutoff [Hz] (see module docstring).
DEFAULT_CUTOFF = 100e3


class LazyModel:
    """Stands for an FE model and assembles it on first attribute access."""

    def __init__(self, build):
        self._build = build
        self._model = None

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if self._model is None:
            self._model = self._build()
        return getattr(self._model, name)


@dataclass
class GearReduction:
    """A reduced gear with its contact data (see module docstring)."""

    gear: object
    body: ReducedBody
    tables: FlankTables
    modal: np.ndarray
    key: str = ""
    info: dict = field(default_factory=dict)
    faults: tuple = ()


def library_versions() -> dict:
    """Versions of the libraries a reduction's numbers depend on (part of a cache key)."""
    import scipy

    return {"numpy": np.__version__, "scipy": scipy.__version__, "skfem": _skfem_version()}


def _skfem_version() -> str:
    """scikit-fem's version from its package metadata (importing skfem takes longer than a
    cached reduction's whole load); the module's ``__version__`` if there is none."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("scikit-fem")
    except PackageNotFoundError:
        import skfem

        return getattr(skfem, "__version__", "?")


def reduction_key(mesh_digest: str, material: Material, thickness: float, formulation: str,
                  options: dict) -> tuple[str, dict]:
    """``(sha256 hex, key dict)`` of a gear reduction."""
    key = {"format": FORMAT_VERSION, "mesh": mesh_digest,
           "material": {"E": float(material.E), "nu": float(material.nu),
                        "rho": float(material.rho)},
           "thickness": float(thickness), "formulation": formulation, "options": options,
           "lanczos_tol": LANCZOS_TOL, "residual_tol": EIGEN_RESIDUAL_TOL,
           "versions": library_versions()}
    s = json.dumps(key, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(s.encode()).hexdigest(), json.loads(s)


def _options(gear, cutoff, support, n_bolts, bolt_circle, bolt_radius, n_points, coupling_points, spread,
             min_spread, depth) -> dict:
    """The reduction options that enter the cache key."""
    options = {"cutoff": float(cutoff), "n_points": int(n_points), "coupling_points": int(coupling_points),
               "spread": float(spread), "min_spread": float(min_spread), "depth": float(depth)}
    if gear.internal:
        options["support"] = support
        if support == "bolts":
            options.update({"n_bolts": n_bolts, "bolt_circle": bolt_circle,
                            "bolt_radius": bolt_radius})
    return options


def _defaults(material, settings, n_points, coupling_points):
    """The arguments :func:`reduce_gear` and :func:`reduction_cached` default: the material,
    the mesh settings and the number of coupling-table radii."""
    if coupling_points is None:
        coupling_points = DEFAULT_COUPLING_POINTS if n_points == DEFAULT_TABLE_POINTS else n_points
    return (Material() if material is None else material, MeshSettings() if settings is None else settings,
            coupling_points)


def _cache_key(gear, material, settings, formulation, options, crack=None) -> tuple[str, dict]:
    """The reduction's cache key (:func:`reduction_key`). It holds the mesh's key, known
    without meshing: a cached gear reads its mesh only when its FE model is needed."""
    digest = mesh_digest(gear, settings) if crack is None else cracked_mesh_digest(gear, crack, settings)
    return reduction_key(digest, material, gear.face_width, formulation, options)


def gear_faults(gear, faults) -> tuple:
    """The faults of non-zero size that the flexible gear ``gear`` is reduced with: spalls,
    chips and missing teeth (material removed from its outline) and at most one root crack (a
    slit in its FE body), each across the whole face width.

    Raises
    ------
    ConfigError
        A partial face width, a tooth out of range or a second crack, naming the fault.
    """
    out = []
    for f in faults or ():
        if f.null:
            continue
        if f.kind not in OUTLINE_FAULTS + ("crack",) or getattr(f, "width_fraction", 1.0) != 1.0:
            raise ConfigError(f"{gear.name}: {f.label()}: a flexible gear is reduced with spalls, chips, missing teeth "
                              "and cracks across the whole face width (width_fraction = 1) only")
        if not 0 <= f.tooth < gear.z:
            raise ConfigError(f"{gear.name}: {f.label()}: tooth must lie in 0..{gear.z - 1}")
        out.append(f)
    cracks = [f for f in out if f.kind == "crack"]
    if len(cracks) > 1:
        raise ConfigError(f"{gear.name}: {cracks[1].label()}: a flexible gear is meshed with one root crack at most "
                          f"({cracks[0].label()} is the first)")
    return tuple(out)


def _crack(meshed, faults: tuple):
    """The :class:`~flexgear.fe.crack.RootCrack` of the gear's crack fault (checked, before any
    meshing), or None."""
    for f in faults:
        if f.kind == "crack":
            return root_crack(meshed, f.depth, f.angle, tooth=f.tooth, side=f.flank, name=f.label())
    return None


def _fault_options(options: dict, faults: tuple) -> dict:
    """``options`` with the faults' records (without the gear's name: the geometry is what counts);
    unchanged for a healthy gear, whose key stays that of a gear reduced without faults."""
    if not faults:
        return options
    recs = []
    for f in faults:
        r = fault_record(f)
        r.pop("gear", None)
        r.pop("planet", None)
        recs.append(r)
    return {**options, "faults": sorted(recs, key=lambda r: json.dumps(r, sort_keys=True))}


def _meshed(gear, faults: tuple):
    """What the FE mesh is built on: the gear, or with outline faults its :class:`FaultyGear`."""
    cut = tuple(f for f in faults if f.kind in OUTLINE_FAULTS)
    return FaultyGear(gear, cut) if cut else gear


def reduction_mesh(gear, settings: MeshSettings | None = None, faults=(), cache_dir=USER_CACHE):
    """The FE mesh (:class:`~flexgear.fe.meshing.GearMesh`) that :func:`reduce_gear` builds the
    gear with ``faults`` on: the faulty outline, a crack as a slit; the plain gear's without."""
    faults = gear_faults(gear, faults)
    meshed = _meshed(gear, faults)
    crack = _crack(meshed, faults)
    if crack is None:
        return mesh_gear(meshed, settings, cache_dir=cache_dir)
    return mesh_cracked_gear(meshed, crack, settings, cache_dir=cache_dir)


def _faulty_key(gear, faults, material, settings, formulation, options):
    """``(faults, meshed gear, crack, digest, key)`` of a reduction with ``faults``, all checked
    before any meshing (:func:`gear_faults`, :func:`_crack`)."""
    faults = gear_faults(gear, faults)
    meshed = _meshed(gear, faults)
    crack = _crack(meshed, faults)
    digest, key = _cache_key(meshed, material, settings, formulation, _fault_options(options, faults), crack)
    return faults, meshed, crack, digest, key


def reduction_cached(gear, material: Material | None = None, settings: MeshSettings | None = None, *,
                     cutoff: float = DEFAULT_CUTOFF, formulation: str = "plane_stress",
                     support: str = "rim", n_bolts: int = DEFAULT_BOLTS,
                     bolt_circle: float | None = None, bolt_radius: float | None = None,
                     n_points: int = DEFAULT_TABLE_POINTS, coupling_points: int | None = None,
                     spread: float = DEFAULT_SPREAD, min_spread: float = MIN_SPREAD,
                     depth: float = DEFAULT_DEPTH, faults=(), cache_dir="meshes/cache") -> bool:
    """Whether :func:`reduce_gear` with these arguments finds a cache entry (its files exist
    with the same key; checksums are verified when it is loaded). Meshes nothing: the mesh's
    key comes from the geometry and the settings (:func:`flexgear.fe.meshing.mesh_digest`).
    False for bad arguments (:func:`reduce_gear` reports them)."""
    if cache_dir is None:
        return False
    try:
        material, settings, coupling_points = _defaults(material, settings, n_points, coupling_points)
        *_, digest, key = _faulty_key(gear, faults, material, settings, formulation,
                                      _options(gear, cutoff, support, n_bolts, bolt_circle, bolt_radius, n_points,
                                               coupling_points, spread, min_spread, depth))
        npz, side = reduction_paths(cache_dir, digest)
        if not (npz.exists() and side.exists() and basis_path(cache_dir, digest).exists()):
            return False
        meta = json.loads(side.read_text())
    except Exception:  # noqa: BLE001 - bad input or a broken sidecar: reduce_gear handles both
        return False
    return meta.get("hash") == digest and meta.get("key") == key


def reduce_gear(gear, material: Material | None = None, settings: MeshSettings | None = None, *,
                cutoff: float = DEFAULT_CUTOFF, formulation: str = "plane_stress",
                support: str = "rim", n_bolts: int = DEFAULT_BOLTS,
                bolt_circle: float | None = None, bolt_radius: float | None = None,
                n_points: int = DEFAULT_TABLE_POINTS, coupling_points: int | None = None,
                spread: float = DEFAULT_SPREAD, min_spread: float = MIN_SPREAD,
                depth: float = DEFAULT_DEPTH, faults=(), cache_dir="meshes/cache",
                progress=None) -> GearReduction:
    """Reduce one gear (Craig-Bampton, bore or ring support tied to the frame) with flank data.

    Parameters
    ----------
    gear : SpurGear
    material : Material, optional
        Steel defaults.
    settings : MeshSettings, optional
        Mesh level and order (default level 2, quadratic).
    cutoff : float
        Fixed-interface mode cutoff [Hz] (> 0 and above the first mode).
    formulation : {"plane_stress", "plane_strain"}
    support, n_bolts, bolt_circle, bolt_radius
        Ring support (see :func:`~flexgear.reduction.interface.gear_interface`).
    n_points, coupling_points, spread, min_spread, depth
        Flank tables (see :func:`~flexgear.reduction.flank.flank_tables`,
        :func:`~flexgear.reduction.flank.coupling_stride`); ``coupling_points = None``: the
        default 17 with the default 129 table radii, else every table radius.
    faults : sequence of ToothFault, optional
        The gear's tooth faults (:func:`gear_faults`): the FE body is meshed on the faulty
        outline (:class:`~flexgear.gears.modified.FaultyGear`) with a crack as a slit
        (:func:`~flexgear.fe.crack.mesh_cracked_gear`), the faulty teeth and their neighbours get
        their own flank tables (:func:`~flexgear.reduction.flank.flank_tables`), and the faults
        enter the cache key. None of non-zero size: the healthy gear, bit for bit.
    cache_dir : path or None
        Cache directory for meshes and reductions (None: no cache).
    progress : callable, optional
        ``progress(str)`` messages.

    Returns
    -------
    GearReduction
    """
    say = progress or (lambda s: None)
    if isinstance(cutoff, bool) or not isinstance(cutoff, (int, float)) \
            or not math.isfinite(cutoff) or cutoff <= 0:
        raise ConfigError(f"{gear.name}: cutoff = {cutoff!r}: the mode cutoff must be a "
                          "frequency > 0 Hz")
    if formulation not in FORMULATIONS:
        raise ConfigError(f"{gear.name}: formulation = {formulation!r}: must be one of "
                          f"{FORMULATIONS}")
    if gear.internal and support not in RING_SUPPORTS:
        raise ConfigError(f"{gear.name}: support = {support!r}: a flexible ring must be held; "
                          f"choose one of {RING_SUPPORTS}")
    material, settings, coupling_points = _defaults(material, settings, n_points, coupling_points)
    t0, cpu0 = time.perf_counter(), time.process_time()
    faults = gear_faults(gear, faults)
    check_meshable(_meshed(gear, faults), settings)  # the mesh's own checks, before any long computation
    coupling_stride(n_points, coupling_points)
    faults, meshed, crack, digest, key = _faulty_key(gear, faults, material, settings, formulation,
                                                     _options(gear, cutoff, support, n_bolts, bolt_circle, bolt_radius,
                                                              n_points, coupling_points, spread, min_spread, depth))
    own = faulty_teeth(faults, gear.z) if faults else []
    ref = reference_tooth(gear.z, own)

    def build_model():
        return assemble(reduction_mesh(gear, settings, faults, cache_dir), material, gear.face_width, formulation)

    with entry_lock(cache_dir, f"reduction-{digest}") if cache_dir is not None else contextlib.nullcontext():
        if cache_dir is not None:
            red = load_reduction(cache_dir, digest, key, gear, LazyModel(build_model), say=say)
            if red is not None:
                red.faults = faults
                red.info["seconds"] = time.perf_counter() - t0
                say(f"{gear.name}: reduction loaded from cache ({red.body.n_modes} modes)")
                return red
        say(f"{gear.name}: meshing, assembling K, M")
        with single_threaded_blas():  # the same bits on any machine
            model = build_model()
            itf = gear_interface(model, gear, support, n_bolts, bolt_circle, bolt_radius)
            say(f"{gear.name}: Craig-Bampton reduction ({model.ndofs} dofs, cutoff {cutoff/1e3:.4g} kHz)")
            body = CraigBamptonReductor(model, itf, cutoff=cutoff).reduce()
            say(f"{gear.name}: {body.n_modes} modes; flank tables")
            radii = table_radii(model, gear, n_points, ref)
            samples = flank_samples(model, gear, radii, SIDES, spread, min_spread, faulty=own)
            tables = flank_tables(body, gear, radii, spread=spread, min_spread=min_spread, depth=depth,
                                  samples=samples, coupling_points=coupling_points, faulty=own)
            modal = modal_table(body, gear, radii, SIDES, samples=samples)
        red = GearReduction(gear=gear, body=body, tables=tables, modal=modal, key=digest,
                            info={"seconds": time.perf_counter() - t0, "source": "computed"}, faults=faults)
        if cache_dir is not None:
            write_reduction(cache_dir, digest, key, red)
    say(timing_message(gear.name, time.perf_counter() - t0, time.process_time() - cpu0, body.info["eigen_seconds"],
                       tables.info["seconds"]))
    return red


def timing_message(name: str, wall: float, cpu: float, eigen: float, tables: float) -> str:
    """What a reduction took [s]: its wall time, the wall time of its two long parts (the
    eigen-solve, the flank tables), and apart, this process's CPU time. On a machine shared with
    other jobs the wall times grow with their load, the CPU time does not."""
    return (f"{name}: reduced in {wall:.1f} s wall time (of which the eigen-solve {eigen:.1f} s, the flank tables "
            f"{tables:.1f} s); {cpu:.1f} s of CPU time in this process")


# --------------------------------------------------------------------------------------------
# cache files
# --------------------------------------------------------------------------------------------
def reduction_paths(cache_dir, digest: str) -> tuple[Path, Path]:
    """Paths ``(.npz, .json)`` of a cache entry (the basis: :func:`basis_path`)."""
    d = Path(cache_dir)
    return d / f"reduction-{digest}.npz", d / f"reduction-{digest}.json"


def basis_path(cache_dir, digest: str) -> Path:
    """Path of a cache entry's basis (``.npy``)."""
    return Path(cache_dir) / f"reduction-{digest}.basis.npy"


def write_reduction(cache_dir, digest: str, key: dict, red: GearReduction) -> Path:
    """Write ``red`` atomically (the basis ``.npy``, the ``.npz``, then the ``.json``)."""
    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    npz, side = reduction_paths(cache_dir, digest)
    bpath = basis_path(cache_dir, digest)
    b, t, im = red.body, red.tables, red.body.interface
    arrays = {"K": b.K, "M": b.M, "frequencies": b.frequencies,
              "omega2": b.modal_stiffness, "boundary": im.boundary, "T": im.T, "fixed": im.fixed,
              "centre": np.asarray(im.centre, float), "radius": t.radius, "modal": red.modal,
              "coupling_radius": t.coupling_radius, "coupling": t.coupling}
    for s in SIDES:
        arrays[f"spread_{s}"] = t.spread[s]
        arrays[f"near_{s}"] = t.near_field[s]
        arrays[f"self_{s}"] = t.self_residual[s]
        arrays[f"static_{s}"] = t.self_static[s]
        arrays[f"fraction_{s}"] = t.modal_fraction[s]

    atomic_write_arrays(bpath, np.asarray(b.basis, float))
    atomic_write_arrays(npz, arrays)
    meta = {"hash": digest, "key": key, "npz_sha256": sha256_file(npz),
            "basis_sha256": sha256_file(bpath), "basis_bytes": bpath.stat().st_size,
            "names": list(b.names), "n_interface": b.n_interface, "method": b.method,
            "rigid": im.rigid, "interface_names": list(im.names), "depth": t.depth,
            "sectors": int(im.sectors), "period": int(t.period)}

    atomic_write_json(side, meta)
    return npz


def _file_stamp(path: Path) -> tuple:
    st = path.stat()
    return st.st_size, st.st_mtime_ns, st.st_ino


def _basis_reader(cache_dir, digest: str, sha256: str, verified: tuple):
    """A callable that reads a cache entry's basis, checking its SHA-256 again if the file
    changed since it was verified (``verified``: its size, mtime and inode then); a corrupt file
    is removed with the entry, and the error says to run again: the entry is rebuilt then."""
    npz, side = reduction_paths(cache_dir, digest)
    bpath = basis_path(cache_dir, digest)

    def read():
        if _file_stamp(bpath) != verified and sha256_file(bpath) != sha256:
            discard_files(side, npz, bpath)
            raise ConfigError(f"reduction cache entry {bpath.name} is corrupt (checksum mismatch); "
                              "it was removed: run again to rebuild it")
        return np.load(bpath)

    return read


def load_reduction(cache_dir, digest: str, key: dict, gear, model, say=None) -> GearReduction | None:
    """Load a cache entry; ``None`` if missing, corrupt or stale (then it is removed, and
    ``say(message)`` or the log tells why). Both files are checked against their SHA-256 here,
    so that no run uses a damaged entry, whether it needs the basis or not; the basis itself
    is read on first use."""
    npz, side = reduction_paths(cache_dir, digest)
    bpath = basis_path(cache_dir, digest)
    if not side.exists() and not npz.exists() and not bpath.exists():
        return None
    try:
        meta = json.loads(side.read_text())
        if meta.get("hash") != digest or meta.get("key") != key:
            raise ValueError("stale cache entry (key mismatch)")
        if sha256_file(npz) != meta["npz_sha256"]:
            raise ValueError(f"{npz.name}: checksum mismatch")
        if bpath.stat().st_size != meta["basis_bytes"]:
            raise ValueError(f"{bpath.name}: size mismatch")
        stamp = _file_stamp(bpath)
        if sha256_file(bpath) != meta["basis_sha256"]:
            raise ValueError(f"{bpath.name}: checksum mismatch")
        with np.load(npz) as z:
            a = {k: z[k] for k in z.files}
        nq = int(meta["n_interface"])
        im = InterfaceMap(a["boundary"], a["T"], a["fixed"], tuple(meta["interface_names"]),
                          rigid=bool(meta["rigid"]), centre=tuple(a["centre"].tolist()),
                          sectors=int(meta["sectors"]))
        factor = ClampedFactorisation(model, np.union1d(im.boundary, im.fixed))
        body = LazyBasisBody(K=a["K"], M=a["M"], basis=_basis_reader(cache_dir, digest, meta["basis_sha256"], stamp),
                             n_interface=nq, frequencies=a["frequencies"], names=tuple(meta["names"]),
                             model=model, interface=im, residual=None, method=meta["method"],
                             info={"source": "cache"})
        body.residual = ResidualFlexibility(factor, lambda: body.basis[:, nq:], a["omega2"])
        tables = FlankTables(
            radius=a["radius"], period=int(meta["period"]), spread={s: a[f"spread_{s}"] for s in SIDES},
            near_field={s: a[f"near_{s}"] for s in SIDES},
            self_residual={s: a[f"self_{s}"] for s in SIDES}, coupling_radius=a["coupling_radius"],
            coupling=a["coupling"],
            self_static={s: a[f"static_{s}"] for s in SIDES},
            modal_fraction={s: a[f"fraction_{s}"] for s in SIDES}, depth=float(meta["depth"]),
            info={"source": "cache"})
        return GearReduction(gear=gear, body=body, tables=tables, modal=a["modal"], key=digest,
                             info={"source": "cache"})
    except Exception as exc:  # noqa: BLE001 - any failure means: rebuild
        msg = f"{gear.name}: cached reduction {npz.stem} unusable ({exc}); removed, rebuilding it"
        if say is not None:
            say(msg)
        else:
            log.warning(msg)
        discard_files(side, npz, bpath)
        return None
