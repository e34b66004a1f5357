"""Files for people: gear meshes and clamped-hub mode shapes as VTU (ParaView) and PNG.

:func:`write_mesh_outputs` writes ``<name>_mesh.vtu`` and ``<name>_mesh.png``;
:func:`write_mode_outputs` writes ``<name>_modes.vtu`` (mode shapes as point data),
``<name>_modes.png`` (first six modes, deformed), ``<name>_modes.csv`` and
``<name>_modes.md`` (frequency tables). Existing files are never overwritten unless
``overwrite=True`` (:class:`~flexgear.errors.ResultExistsError`); all targets are checked
before anything is written. Figures use the project's publication style
(:func:`flexgear.style.paper_style`), coordinates shown in mm.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import atomic_write, check_targets
from ..errors import ConfigError
from .elasticity import FORMULATIONS, assemble, clamped_modes
from ..gears.material import Material
from .meshing import USER_CACHE, GearMesh, MeshSettings, mesh_gear

#: Number of modes drawn in the mode figure.
N_PLOT_MODES = 6


def _save_png(fig, path: Path):
    from ..style import save_figure

    save_figure(fig, path, overwrite=True)  # targets were checked before anything was written


def _cells(gm: GearMesh):
    return [("triangle6" if gm.order == 2 else "triangle", gm.triangles)]


def _points3(gm: GearMesh):
    return np.column_stack([gm.points, np.zeros(gm.n_nodes)])


def _clamp_group(gear, gm: GearMesh) -> str:
    name = "rim" if getattr(gear, "internal", False) else "hub"
    if name not in gm.node_sets:
        raise ConfigError(f"{getattr(gear, 'name', 'gear')}: no '{name}' boundary to clamp "
                          "(an external gear needs bore_diameter > 0)")
    return name


def _sub_triangles(gm: GearMesh) -> np.ndarray:
    """Linear triangles for plotting: each 6-node triangle split into 4."""
    t = gm.triangles
    if gm.order == 1:
        return t
    return np.vstack([t[:, [0, 3, 5]], t[:, [3, 1, 4]], t[:, [5, 4, 2]], t[:, [3, 4, 5]]])


def _edge_polylines(gm: GearMesh, xy: np.ndarray, boundary_only=False) -> np.ndarray:
    """Unique element edges as polylines (K, 2 or 3, 2) through their nodes [m]."""
    t = gm.triangles
    if gm.order == 2:
        e = np.vstack([t[:, [0, 3, 1]], t[:, [1, 4, 2]], t[:, [2, 5, 0]]])
    else:
        e = np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    ends = np.sort(e[:, [0, -1]], axis=1)
    _, idx, cnt = np.unique(ends, axis=0, return_index=True, return_counts=True)
    sel = idx[cnt == 1] if boundary_only else idx
    return xy[e[sel]]


def _mesh_axes(ax, title=None):
    ax.set_aspect("equal")
    ax.grid(False)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    if title:
        ax.set_title(title)


def mesh_figure(gm: GearMesh, title: str):
    """Figure of the mesh: all element edges as thin lines, boundary darker; axes in mm."""
    from matplotlib.collections import LineCollection

    from ..style import figure, paper_style

    with paper_style():
        fig = figure(5.0, 5.0)
        ax = fig.add_subplot()
        xy = gm.points * 1e3
        ax.add_collection(LineCollection(_edge_polylines(gm, xy), linewidths=0.15, colors="0.35"))
        ax.add_collection(LineCollection(_edge_polylines(gm, xy, True), linewidths=0.5, colors="k"))
        ax.autoscale_view()
        _mesh_axes(ax, title)
    return fig


def modes_figure(gm: GearMesh, nodal: np.ndarray, freqs: np.ndarray, title: str,
                 amplitude: float | None = None):
    """Figure of mode shapes: deformed meshes coloured by |u|, frequency in each title.

    Parameters
    ----------
    nodal : ndarray (n_nodes, 2, k)
        Nodal mode shapes.
    freqs : ndarray (k,)
        Frequencies [Hz].
    amplitude : float, optional
        Largest drawn displacement [m]; default 4 % of the body's outer radius.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation

    from ..style import figure, paper_style

    k = nodal.shape[2]
    ncol = min(3, k)
    nrow = int(np.ceil(k / ncol))
    r_out = float(np.max(np.hypot(*gm.points.T)))
    amp = 0.04 * r_out if amplitude is None else amplitude
    tri = _sub_triangles(gm)
    axes = []
    with paper_style():
        fig = figure(2.4 * ncol, 2.5 * nrow + 0.3)
        fig.suptitle(title)
        for i in range(k):
            ax = fig.add_subplot(nrow, ncol, i + 1)
            u = nodal[:, :, i]
            mag = np.hypot(u[:, 0], u[:, 1])
            s = amp / max(float(mag.max()), 1e-300)
            xy = (gm.points + s * u) * 1e3
            ax.add_collection(LineCollection(_edge_polylines(gm, gm.points * 1e3, True),
                                             linewidths=0.3, colors="0.7"))
            tr = Triangulation(xy[:, 0], xy[:, 1], tri)
            pc = ax.tripcolor(tr, mag / mag.max(), shading="gouraud", cmap="viridis", vmin=0,
                              vmax=1, rasterized=True)
            axes.append(ax)
            ax.add_collection(LineCollection(_edge_polylines(gm, xy, True), linewidths=0.3,
                                             colors="k"))
            ax.autoscale_view()
            _mesh_axes(ax, f"mode {i + 1}: {freqs[i] / 1e3:.3f} kHz")
        fig.colorbar(pc, ax=axes, shrink=0.6, label=r"$|u| / \max |u|$")
    return fig


def _gear_name(gear) -> str:
    return str(getattr(gear, "name", "gear") or "gear")


def mesh_output_paths(gear, outdir) -> list[Path]:
    """Files :func:`write_mesh_outputs` writes for ``gear`` into ``outdir``: VTU, PNG."""
    name = _gear_name(gear)
    return [Path(outdir) / f"{name}_mesh.vtu", Path(outdir) / f"{name}_mesh.png"]


def mode_output_paths(gear, outdir) -> list[Path]:
    """Files :func:`write_mode_outputs` writes for ``gear`` into ``outdir``: VTU, PNG, CSV, MD."""
    name = _gear_name(gear)
    return [Path(outdir) / f"{name}_modes.{ext}" for ext in ("vtu", "png", "csv", "md")]


def write_mesh_outputs(gear, material: Material, settings: MeshSettings | None, outdir, *,
                       overwrite: bool = False, cache_dir=USER_CACHE) -> dict:
    """Mesh ``gear`` and write ``<name>_mesh.vtu`` and ``<name>_mesh.png`` into ``outdir``.

    Parameters
    ----------
    gear : flexgear.geometry.SpurGear
    material : Material
        Recorded in the VTU field data (E [Pa], nu, rho [kg/m^3]).
    settings : MeshSettings or None
        Mesh settings (default ``MeshSettings()``).
    outdir : str or PathLike
        Output directory (created).
    overwrite : bool
        Replace existing files; otherwise :class:`~flexgear.errors.ResultExistsError`.
    cache_dir : path or None
        Mesh cache directory (see :func:`flexgear.fe.meshing.mesh_gear`).

    Returns
    -------
    list of Path
        ``[<name>_mesh.vtu, <name>_mesh.png]``.
    """
    import meshio

    settings = settings or MeshSettings()
    outdir = Path(outdir)
    name = _gear_name(gear)
    vtu, png = mesh_output_paths(gear, outdir)
    check_targets([vtu, png], overwrite)
    gm = mesh_gear(gear, settings, cache_dir=cache_dir)
    outdir.mkdir(parents=True, exist_ok=True)
    mesh = meshio.Mesh(_points3(gm), _cells(gm),
                       cell_data={"min_angle_deg": [gm.min_angles()]},
                       field_data={"E_Pa": np.array([material.E]), "nu": np.array([material.nu]),
                                   "rho_kg_m3": np.array([material.rho]),
                                   "face_width_m": np.array([float(gear.face_width)])})
    atomic_write(vtu, lambda p: meshio.write(p, mesh, file_format="vtu"))
    kind = "P2" if gm.order == 2 else "P1"
    fig = mesh_figure(gm, f"{name}: {gm.n_elements} triangles ({kind}), level {settings.level}")
    _save_png(fig, png)
    return [vtu, png]


def clamped_gear_modes(gear, material: Material, settings: MeshSettings | None = None,
                       n_modes: int = 10, formulation: str = "plane_stress",
                       cache_dir=USER_CACHE):
    """Mesh, assemble and solve the clamped-hub (external) / clamped-rim (internal) modes.

    Returns
    -------
    gm : GearMesh
    model : FEModel
    freqs : ndarray (n_modes,)
        Natural frequencies [Hz].
    shapes : ndarray (ndofs, n_modes)
        Mass-normalised mode shapes.
    """
    if formulation not in FORMULATIONS:
        raise ConfigError(f"formulation = {formulation!r}: must be one of {FORMULATIONS}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ConfigError(f"n_modes = {n_modes!r}: must be an integer >= 1")
    gm = mesh_gear(gear, settings or MeshSettings(), cache_dir=cache_dir)
    clamp = _clamp_group(gear, gm)
    model = assemble(gm, material, float(gear.face_width), formulation)
    freqs, shapes = clamped_modes(model, model.group_dofs(clamp), n_modes)
    return gm, model, freqs, shapes


def write_mode_outputs(gear, material: Material, settings: MeshSettings | None, outdir,
                       n_modes: int = 10, formulation: str = "plane_stress", *,
                       overwrite: bool = False, cache_dir=USER_CACHE) -> dict:
    """Clamped-hub natural modes of ``gear``: VTU, PNG and frequency tables.

    The bore (``hub``) of an external gear, or the outer ``rim`` of an internal gear, is
    clamped; the body is a plane-stress (default) or plane-strain slice of thickness
    ``gear.face_width``.

    Parameters
    ----------
    gear : flexgear.geometry.SpurGear
    material : Material
    settings : MeshSettings or None
    outdir : str or PathLike
    n_modes : int
        Number of modes computed and written (>= 1).
    formulation : {"plane_stress", "plane_strain"}
    overwrite : bool
        Replace existing files; otherwise :class:`~flexgear.errors.ResultExistsError`.
    cache_dir : path or None
        Mesh cache directory (see :func:`flexgear.fe.meshing.mesh_gear`).

    Returns
    -------
    list of Path
        ``[<name>_modes.vtu, .png, .csv, .md]`` (frequencies: see the CSV, or
        :func:`clamped_gear_modes` for the arrays).
    """
    import meshio

    settings = settings or MeshSettings()
    outdir = Path(outdir)
    name = _gear_name(gear)
    paths = dict(zip(("vtu", "png", "csv", "md"), mode_output_paths(gear, outdir)))
    check_targets(paths.values(), overwrite)

    gm, model, freqs, shapes = clamped_gear_modes(gear, material, settings, n_modes,
                                                  formulation, cache_dir)
    clamp = _clamp_group(gear, gm)
    nodal = model.nodal_field(shapes)  # (n_nodes, 2, n_modes)
    outdir.mkdir(parents=True, exist_ok=True)

    width = len(str(n_modes))
    pdata = {f"mode{i + 1:0{width}d}": np.column_stack([nodal[:, :, i], np.zeros(gm.n_nodes)])
             for i in range(n_modes)}
    mesh = meshio.Mesh(_points3(gm), _cells(gm), point_data=pdata,
                       field_data={"frequencies_Hz": np.asarray(freqs)})
    atomic_write(paths["vtu"], lambda p: meshio.write(p, mesh, file_format="vtu"))

    k = min(N_PLOT_MODES, n_modes)
    clamp_txt = "rim" if clamp == "rim" else "hub"
    title = (f"{name}: clamped-{clamp_txt} modes, {formulation.replace('_', ' ')}, "
             f"{gm.n_elements} triangles")
    fig = modes_figure(gm, nodal[:, :, :k], freqs[:k], title)
    _save_png(fig, paths["png"])

    def csv(p):
        with open(p, "w") as fh:
            fh.write("mode,frequency_Hz\n")
            for i, f in enumerate(freqs):
                fh.write(f"{i + 1},{f:.6f}\n")

    def md(p):
        with open(p, "w") as fh:
            fh.write(f"# {name}: clamped-{clamp_txt} natural frequencies\n\n")
            fh.write(f"{formulation.replace('_', ' ')}, E = {material.E:.4g} Pa, "
                     f"nu = {material.nu:g}, rho = {material.rho:g} kg/m^3, face width "
                     f"{float(gear.face_width) * 1e3:g} mm; mesh level {settings.level}, "
                     f"order {settings.order}, {gm.n_elements} triangles, "
                     f"{model.ndofs} dofs.\n\n")
            fh.write("| mode | frequency [Hz] |\n|---:|---:|\n")
            for i, f in enumerate(freqs):
                fh.write(f"| {i + 1} | {f:.1f} |\n")

    atomic_write(paths["csv"], csv)
    atomic_write(paths["md"], md)
    return list(paths.values())
