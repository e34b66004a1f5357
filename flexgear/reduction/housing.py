"""The housing, reduced and cached: mesh -> FE model -> Craig-Bampton body with named patches.

:func:`reduce_housing` returns a :class:`HousingReduction` whose interface is a set of rigid
*patches* (:class:`PatchInterface`), each with ``(u_x, u_y, theta)`` [m, m, rad] of a frame at
its centre: ``seat_<name>`` (a bearing seat's bore; ``patch.shafts`` the shafts it carries,
coaxial shafts sharing one seat), ``bolt<k>`` (ring bolt hole k) and ``foot<k>`` (a foot pad,
held to ground by springs of ``foot_stiffness``, kept out of ``K`` so the cache does not depend
on it: :meth:`HousingReduction.ground_stiffness`).

Coordinates ``q = [patch coordinates (3 per patch, in order), eta]``: fixed-interface modes up
to the cutoff, then the modal truncation augmentation vectors
(:meth:`~flexgear.reduction.reductor.CraigBamptonReductor.augmentation`), all mass-normalised,
stiffness block diagonal (``body.frequencies`` lists both; ``body.info["augmentation_vectors"]``
counts the latter). Loads reach the housing only at patches, where the constraint modes are
exact, so no residual flexibility is kept. Sensors are outputs, not interface nodes (no load,
mass neglected): their recovery rows (:mod:`flexgear.reduction.recovery`) interpolate the basis,
so a sensor neither enlarges the model nor invalidates the cache.

Cache: ``<cache_dir>/housing-<sha256>.npz``, ``.basis.npy`` and a ``.json`` sidecar with the key
and both files' SHA-256, verified at every load, written atomically (basis, npz, sidecar). The
key holds :meth:`~flexgear.gears.housing.Housing.mesh_key`, :data:`FORMAT_VERSION`, gmsh and
library versions and eigen-solver tolerances; a missing, corrupt or stale entry is rebuilt. A
cached housing loads without gmsh; its FE model is assembled on first use.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..files import atomic_write_arrays, atomic_write_json, discard_files, entry_lock, sha256_file
from ..fe.elasticity import EIGEN_RESIDUAL_TOL, LANCZOS_TOL, single_threaded_blas
from ..fe.housing import assemble_housing, mesh_housing
from ..fe.meshing import USER_CACHE, GearMesh, resolve_cache_dir
from ..gears.housing import Housing
from .body import ReducedBody
from .gear import LazyModel, library_versions
from .interface import InterfaceMap
from .recovery import PointLocator, recovery_row, rigid_row
from .reductor import CraigBamptonReductor

log = logging.getLogger(__name__)

#: Bump when the cached content or the reduction changes (invalidates old entries).
FORMAT_VERSION = 2  # 2: modal truncation augmentation
PATCH_COORDINATES = ("ux", "uy", "theta")


@dataclass(frozen=True)
class Patch:
    """A rigid patch of the housing's interface (module docstring).

    Attributes
    ----------
    name : str
        ``seat_<name>``, ``bolt<k>`` or ``foot<k>`` (the mesh's boundary group).
    role : str
        ``"seat"``, ``"bolt"`` or ``"foot"``.
    centre : tuple
        Frame origin [m]: the hole's centre, the pad's centre on the outline.
    coordinates : tuple of int
        Indices of its ``(u_x, u_y, theta)`` in the reduced coordinates.
    shafts : tuple of str
        The shafts a seat carries (empty for bolts and feet).
    """

    name: str
    role: str
    centre: tuple
    coordinates: tuple
    shafts: tuple = ()


class PatchInterface:
    """Several node sets, each tied rigidly to its own frame (3 coordinates per patch).

    Parameters
    ----------
    patches : sequence of (name, nodes, centre)
        Node indices of each patch and its frame origin [m]; patches share no node.
    """

    def __init__(self, patches):
        self.patches = [(str(n), np.unique(np.asarray(nodes, np.int64)), (float(c[0]), float(c[1])))
                        for n, nodes, c in patches]

    def resolve(self, model) -> InterfaceMap:
        rows, cols, vals, dofs = [], [], [], []
        names = []
        seen = np.zeros(model.n_nodes, bool)
        for p, (name, nodes, c) in enumerate(self.patches):
            if nodes.size < 2:
                raise ConfigError(f"patch {name}: {nodes.size} node(s); a rigid patch needs at least two")
            if seen[nodes].any():
                raise ConfigError(f"patch {name} shares nodes with another patch")
            seen[nodes] = True
            x = model.node_coords[nodes]
            d = model.nodal_dofs(nodes)
            dx, dy = x[:, 0] - c[0], x[:, 1] - c[1]
            for comp, col_vals in ((0, (1.0, 0.0, -dy)), (1, (0.0, 1.0, dx))):
                for j, v in enumerate(col_vals):
                    v = np.broadcast_to(np.asarray(v, float), nodes.shape)
                    rows.append(d[:, comp])
                    cols.append(np.full(nodes.size, 3 * p + j))
                    vals.append(v)
            dofs.append(d.ravel())
            names += [f"{name}.{c_}" for c_ in PATCH_COORDINATES]
        boundary = np.sort(np.concatenate(dofs))
        pos = np.searchsorted(boundary, np.concatenate(rows))
        T = np.zeros((boundary.size, 3 * len(self.patches)))
        np.add.at(T, (pos, np.concatenate(cols)), np.concatenate(vals))
        return InterfaceMap(boundary, T, np.zeros(0, np.int64), tuple(names))


@dataclass
class HousingReduction:
    """A reduced housing (module docstring).

    Attributes
    ----------
    housing : Housing
    body : ReducedBody
        ``K``, ``M`` [SI per coordinate], ``basis`` (ndofs, n), ``names``, ``frequencies``
        (fixed-interface, Hz); the foot springs are not in ``K``.
    patches : tuple of Patch
    mesh : GearMesh
        The mesh the basis lives on (regions ``wall`` and ``cover``).
    node_dofs : ndarray (n_nodes, 2)
    key : str
        The cache key's SHA-256.
    info : dict
        Timings, sizes, ``source`` (``"computed"`` or ``"cache"``).
    """

    housing: Housing
    body: ReducedBody
    patches: tuple
    mesh: GearMesh
    node_dofs: np.ndarray
    key: str = ""
    info: dict = field(default_factory=dict)
    _locator: PointLocator | None = field(default=None, repr=False)

    @property
    def n(self) -> int:
        """Number of reduced coordinates."""
        return self.body.n

    def patch(self, name: str) -> Patch:
        """The patch named ``name`` (``seat_centre``, ``bolt3``, ``foot0``)."""
        for p in self.patches:
            if p.name == name:
                return p
        raise ConfigError(f"housing has no patch {name!r}; patches: {', '.join(p.name for p in self.patches)}")

    def role(self, role: str) -> tuple:
        """The patches of one role (``seat``, ``bolt``, ``foot``), in order."""
        return tuple(p for p in self.patches if p.role == role)

    def seat(self, shaft: str) -> Patch:
        """The seat that carries ``shaft`` (``sun``, ``carrier``, ``pinion``, ``wheel``)."""
        for p in self.role("seat"):
            if shaft in p.shafts:
                return p
        have = sorted(s for p in self.role("seat") for s in p.shafts)
        raise ConfigError(f"housing has no seat for shaft {shaft!r}; seats carry {', '.join(have) or 'nothing'}")

    def ground_stiffness(self) -> np.ndarray:
        """(n, n) stiffness of the foot springs on the feet's ``u_x, u_y`` [N/m]."""
        K = np.zeros((self.n, self.n))
        for p in self.role("foot"):
            i, j = p.coordinates[:2]
            K[i, i] += self.housing.foot_stiffness
            K[j, j] += self.housing.foot_stiffness
        return K

    def ring_coupling(self, centre=(0.0, 0.0)) -> np.ndarray:
        """(n, 3) map from a rigid ring's frame coordinates ``(u_x, u_y, theta)`` about ``centre``
        to the reduced coordinates of the bolt patches (zero elsewhere): the bolt shanks move
        with the ring. Its transpose maps the housing's generalised forces on the bolts to the
        ring's force and moment. A load ``(F_x, F_y, M_z)`` [N, N, N m] the ring puts on the
        housing is not ``E F`` (that puts all of F on every bolt): on bolts tied to the ring it
        loads the ring's coordinates (:class:`~flexgear.reduction.paths.TransferPath`); shared
        out over free bolts, ``E (E^T E)^-1 F`` is its statically equivalent least-norm share
        (:func:`~flexgear.reduction.paths.housing_inputs`)."""
        E = np.zeros((self.n, 3))
        for p in self.role("bolt"):
            ix, iy, it = p.coordinates
            rx, ry = p.centre[0] - centre[0], p.centre[1] - centre[1]
            E[ix] = (1.0, 0.0, -ry)
            E[iy] = (0.0, 1.0, rx)
            E[it] = (0.0, 0.0, 1.0)
        return E

    def force_at(self, patch: Patch) -> np.ndarray:
        """(n, 2) generalised forces of a force ``(F_x, F_y)`` [N] at a patch's centre."""
        B = np.zeros((self.n, 2))
        B[patch.coordinates[0], 0] = 1.0
        B[patch.coordinates[1], 1] = 1.0
        return B

    @property
    def locator(self) -> PointLocator:
        if self._locator is None:
            self._locator = PointLocator(self.mesh.points, self.mesh.triangles)
        return self._locator

    def sensor_row(self, point, direction, what: str = "sensor") -> np.ndarray:
        """(n,) row: the displacement along unit ``direction`` at ``point`` [m] is ``row . q``
        (:func:`~flexgear.reduction.recovery.recovery_row`)."""
        return recovery_row(self.locator, self.node_dofs, self.body.basis, point, direction, what)

    def sensor_rows(self, sensors) -> np.ndarray:
        """(n_sensors, n) rows of the ``body = "housing"`` sensors given (a Sensor sequence)."""
        rows = []
        for s in sensors:
            if s.body != "housing":
                raise ConfigError(f"sensor {s.name!r} is on the {s.body}, not on the housing "
                                  "(a rigid ring's row: flexgear.reduction.recovery.rigid_row)")
            rows.append(self.sensor_row(s.point, s.direction, f"sensor {s.name!r}"))
        return np.array(rows).reshape(len(rows), self.n)


def housing_patches(housing: Housing, mesh: GearMesh) -> list:
    """``(name, role, nodes, centre, shafts)`` of every patch: seats, bolts, feet."""
    out = [(f"seat_{s.name}", "seat", mesh.node_sets[f"seat_{s.name}"], tuple(s.centre), tuple(s.shafts))
           for s in housing.seats]
    if housing.bolts is not None:
        out += [(f"bolt{k}", "bolt", mesh.node_sets[f"bolt{k}"], tuple(c), ()) for k, c in
                enumerate(housing.bolts.positions().tolist())]
    out += [(f"foot{k}", "foot", mesh.node_sets[f"foot{k}"], tuple(c), ()) for k, c in
            enumerate(housing.foot_points().tolist())]
    return out


def housing_key(housing: Housing) -> tuple[str, dict]:
    """``(sha256 hex, key dict)`` of a housing reduction."""
    import gmsh

    key = {"format": FORMAT_VERSION, "housing": housing.mesh_key(), "gmsh": getattr(gmsh, "__version__", "?"),
           "lanczos_tol": LANCZOS_TOL, "residual_tol": EIGEN_RESIDUAL_TOL, "versions": library_versions()}
    s = json.dumps(key, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(s.encode()).hexdigest(), json.loads(s)


def reduce_housing(housing: Housing, cache_dir=USER_CACHE, progress=None) -> HousingReduction:
    """Mesh, assemble and reduce (Craig-Bampton, ``housing.cutoff``) the housing, cached.

    Parameters
    ----------
    housing : Housing
        Checked geometry (:meth:`~flexgear.gears.housing.Housing.check`, which the configuration layer calls).
    cache_dir : path, USER_CACHE or None
        Cache directory (default the per-user mesh cache; None: no cache).
    progress : callable, optional
        ``progress(str)`` messages.

    Raises
    ------
    ConfigError
        A cutoff below the first fixed-interface mode, or a housing without a support (no
        patch): it cannot be reduced on its interface.
    """
    say = progress or (lambda s: None)
    t0, cpu0 = time.perf_counter(), time.process_time()
    digest, key = housing_key(housing)
    cache_dir = resolve_cache_dir(cache_dir)
    with entry_lock(cache_dir, f"housing-{digest}") if cache_dir is not None else contextlib.nullcontext():
        if cache_dir is not None:
            red = load_housing(cache_dir, digest, key, housing, say)
            if red is not None:
                red.info["seconds"] = time.perf_counter() - t0
                say(f"housing: reduction loaded from cache ({red.body.n_modes} modes)")
                return red
        if not (housing.seats or housing.bolts or housing.feet):
            raise ConfigError("housing: no seats, bolts or feet: a reduced housing needs an interface")
        say("housing: meshing, assembling K, M")
        mesh = mesh_housing(housing)
        t1 = time.perf_counter()
        model = assemble_housing(housing, mesh)
        t2 = time.perf_counter()
        spec = housing_patches(housing, mesh)
        itf = PatchInterface([(name, nodes, c) for name, _, nodes, c, _ in spec])
        say(f"housing: Craig-Bampton reduction ({model.ndofs} dofs, {3 * len(spec)} interface coordinates, "
            f"cutoff {housing.cutoff / 1e3:.4g} kHz)")
        with single_threaded_blas():  # the same bits on any machine
            try:
                body = CraigBamptonReductor(model, itf, cutoff=housing.cutoff, augment=True).reduce()
            except ConfigError as exc:  # name the table the cutoff is in
                raise ConfigError(f"housing.{exc}") from None
        body.residual = None  # loads act on the patches only, where the constraint modes are exact
        patches = tuple(Patch(name, role, c, (3 * k, 3 * k + 1, 3 * k + 2), shafts)
                        for k, (name, role, _, c, shafts) in enumerate(spec))
        red = HousingReduction(housing, body, patches, mesh, model.node_dofs, key=digest,
                               info={"source": "computed", "ndofs": model.ndofs, "mesh_seconds": t1 - t0,
                                     "assemble_seconds": t2 - t1, "reduce_seconds": body.info["seconds"]})
        if cache_dir is not None:
            write_housing(cache_dir, digest, key, red)
    red.info["seconds"] = time.perf_counter() - t0
    red.info["cpu_seconds"] = time.process_time() - cpu0
    say(f"housing: reduced in {red.info['seconds']:.1f} s wall time ({body.n_modes} modes, {body.n} coordinates); "
        f"{red.info['cpu_seconds']:.1f} s of CPU time in this process")
    return red


# --------------------------------------------------------------------------------------------
# cache files
# --------------------------------------------------------------------------------------------
def housing_paths(cache_dir, digest: str) -> tuple[Path, Path, Path]:
    """Paths ``(.npz, .basis.npy, .json)`` of a cache entry."""
    d = Path(cache_dir)
    return d / f"housing-{digest}.npz", d / f"housing-{digest}.basis.npy", d / f"housing-{digest}.json"


def write_housing(cache_dir, digest: str, key: dict, red: HousingReduction) -> Path:
    """Write ``red`` atomically (the basis, the ``.npz``, then the sidecar)."""
    Path(cache_dir).mkdir(parents=True, exist_ok=True)
    npz, bpath, side = housing_paths(cache_dir, digest)
    b, im, m = red.body, red.body.interface, red.mesh
    groups = sorted(m.facet_groups)
    arrays = {"K": b.K, "M": b.M, "frequencies": b.frequencies, "boundary": im.boundary, "T": im.T,
              "points": m.points, "triangles": m.triangles, "node_dofs": red.node_dofs,
              **{f"region_{r}": v for r, v in m.regions.items()},
              **{f"group_{g}": m.facet_groups[g] for g in groups}}

    atomic_write_arrays(bpath, np.asarray(b.basis, float))
    atomic_write_arrays(npz, arrays)
    meta = {"hash": digest, "key": key, "npz_sha256": sha256_file(npz), "basis_sha256": sha256_file(bpath),
            "names": list(b.names), "n_interface": b.n_interface, "interface_names": list(im.names),
            "order": m.order, "regions": sorted(m.regions), "groups": groups,
            "patches": [{"name": p.name, "role": p.role, "centre": list(p.centre), "coordinates": list(p.coordinates),
                         "shafts": list(p.shafts)} for p in red.patches],
            "info": {k: v for k, v in red.info.items() if isinstance(v, (int, float, str))}}
    atomic_write_json(side, meta)
    return npz


def load_housing(cache_dir, digest: str, key: dict, housing: Housing, say=None) -> HousingReduction | None:
    """Load a cache entry after checking both files' SHA-256; ``None`` if missing, corrupt or
    stale (then removed, and ``say`` or the log tells why)."""
    npz, bpath, side = housing_paths(cache_dir, digest)
    if not (side.exists() or npz.exists() or bpath.exists()):
        return None
    try:
        meta = json.loads(side.read_text())
        if meta.get("hash") != digest or meta.get("key") != key:
            raise ValueError("stale cache entry (key mismatch)")
        for path, sha in ((npz, meta["npz_sha256"]), (bpath, meta["basis_sha256"])):
            if sha256_file(path) != sha:
                raise ValueError(f"{path.name}: checksum mismatch")
        with np.load(npz) as z:
            a = {k: z[k] for k in z.files}
        basis = np.load(bpath)
        mesh = GearMesh(a["points"], a["triangles"], int(meta["order"]),
                        {g: a[f"group_{g}"] for g in meta["groups"]}, key=digest, info={"source": "cache"},
                        regions={r: a[f"region_{r}"] for r in meta["regions"]})
        im = InterfaceMap(a["boundary"], a["T"], np.zeros(0, np.int64), tuple(meta["interface_names"]))
        model = LazyModel(lambda: assemble_housing(housing, mesh))
        body = ReducedBody(K=a["K"], M=a["M"], basis=basis, n_interface=int(meta["n_interface"]),
                           frequencies=a["frequencies"], names=tuple(meta["names"]), model=model, interface=im,
                           residual=None, method="craig_bampton", info={"source": "cache"})
        patches = tuple(Patch(p["name"], p["role"], tuple(p["centre"]), tuple(p["coordinates"]), tuple(p["shafts"]))
                        for p in meta["patches"])
        if basis.shape != (2 * mesh.n_nodes, body.n) or body.K.shape != (body.n, body.n):
            raise ValueError("array shapes disagree")
        return HousingReduction(housing, body, patches, mesh, a["node_dofs"], key=digest,
                                info={**meta.get("info", {}), "source": "cache"})
    except Exception as exc:  # noqa: BLE001 - any failure means: rebuild
        msg = f"housing: cached reduction {npz.stem} unusable ({exc}); removed, rebuilding it"
        (say or log.warning)(msg)
        discard_files(side, npz, bpath)
        return None


def ring_sensor_row(sensor, centre=(0.0, 0.0)) -> np.ndarray:
    """(3,) row of a sensor on a rigid ring: its displacement from the ring's ``(u_x, u_y,
    theta)`` about ``centre`` (:func:`~flexgear.reduction.recovery.rigid_row`)."""
    if sensor.body != "ring":
        raise ConfigError(f"sensor {sensor.name!r} is on the {sensor.body}, not on the ring")
    return rigid_row(sensor.point, sensor.direction, centre)
