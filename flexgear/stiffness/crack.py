"""Single-pair mesh stiffness of a tooth with a root crack, from the plane FE of the cracked gear.

The cracked tooth is meshed as a slit (:mod:`flexgear.fe.crack`) and goes through the same FE as
the healthy one (:func:`~flexgear.stiffness.compliance.tooth_compliance`,
:func:`~flexgear.stiffness.loaded_mesh.loaded_mesh`). The crack sits on tooth 0's left fillet
(that of the loaded flank); by symmetry the tables hold for any tooth and flank. Gives
:func:`crack_pair_stiffness` (healthy, cracked stiffness and the extra compliance ``delta_c``
[m/N]), :func:`partial_width_stiffness` (slices in parallel), the cached tables of the dynamic
models (:func:`crack_ratio_table`: the rigid law's stiffness ratio; :func:`crack_series_table`:
the compliant law's series compliance), :func:`rigid_crack_errors` (the
rigid-model representations against the FE) and :func:`crack_convergence`. See the theory page
*Root crack*. All SI: m, N, N/m, m/N, rad.
"""
from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..files import discard_files, entry_lock, jsonable, read_cached_arrays, user_cache_dir, write_cached_arrays
from ..gears.geometry import gear_parameters
from ..fe.convergence import RichardsonResult, richardson
from ..fe.crack import CrackMesh, RootCrack, mesh_cracked_gear, root_crack
from ..fe.elasticity import assemble
from ..fe.meshing import USER_CACHE, MeshSettings, mesh_gear
from ..gears.material import Material
from .compliance import DEFAULT_POSITIONS, roll_angle, tooth_compliance
from .impact_fit import fit_impact_to_te, zone_mean_te
from .loaded_mesh import ON_PATH, MeshStiffness, loaded_mesh

log = logging.getLogger(__name__)

#: Default formulation: plane strain, as the flexible presets (b/m = 10).
DEFAULT_FORMULATION = "plane_strain"


def cracked_gear_model(gear, crack: RootCrack, settings: MeshSettings | None = None,
                       material: Material | None = None, formulation: str = DEFAULT_FORMULATION,
                       cache_dir=USER_CACHE, crack_mesh: CrackMesh | None = None):
    """Mesh ``gear`` with ``crack`` and assemble it (thickness = face width): (FEModel, GearMesh)."""
    material = Material() if material is None else material
    gm = mesh_cracked_gear(gear, crack, settings, cache_dir=cache_dir, crack_mesh=crack_mesh)
    return assemble(gm, material, gear.face_width, formulation), gm


@dataclass
class CrackPairStiffness:
    """Single-pair stiffness of a pair with one cracked tooth, over the path of contact.

        Attributes
        ----------
        pair : GearPair
        cracked : int
            1 or 2: which gear carries the crack (tooth 0, left fillet).
        crack : RootCrack
        load : float
            Normal load of the pair [N].
        roll : ndarray (J,)
            Roll angle tan(alpha_y) of the cracked gear's contact [rad].
        k_healthy, k_cracked : ndarray (J,)
            Single-pair stiffness [N/m] (NaN off the path).
        delta_c : ndarray (J,)
            Extra compliance of the cracked tooth, c_cracked - c_healthy (bulk) [m/N].
        healthy, cracked_mesh : MeshStiffness
            The FE loaded meshes (the cracked one with every tooth of the cracked gear cracked:
            only its ``k_single`` and compliance tables are used).
        info : dict
            Mesh sizes and dof counts.
    """

    pair: object
    cracked: int
    crack: RootCrack
    load: float
    roll: np.ndarray
    k_healthy: np.ndarray
    k_cracked: np.ndarray
    delta_c: np.ndarray
    healthy: MeshStiffness
    cracked_mesh: MeshStiffness
    info: dict

    @property
    def ratio(self) -> np.ndarray:
        """k_cracked / k_healthy along the path [-]."""
        return self.k_cracked / self.k_healthy

    @property
    def on_path(self) -> np.ndarray:
        """Grid points on the path of contact (bool)."""
        return self.healthy.grid.tip == ON_PATH

    def at_load(self, load: float) -> tuple[np.ndarray, np.ndarray]:
        """(k_healthy, k_cracked) [N/m] at another load [N] (same FE tables; Hertz re-evaluated)."""
        kw = dict(formulation=self.healthy.c1.formulation, hertz=self.healthy.hertz,
                  n_positions=self.healthy.grid.n)
        h = loaded_mesh(self.pair, load, compliances=(self.healthy.c1, self.healthy.c2), **kw)
        c = loaded_mesh(self.pair, load, compliances=(self.cracked_mesh.c1, self.cracked_mesh.c2), **kw)
        return h.k_single, c.k_single


def crack_pair_stiffness(pair, depth: float, angle: float, load: float, *, cracked: int = 1,
                         start_tangent: float | None = None, start_radius: float | None = None,
                         settings: MeshSettings | None = None, material: Material | None = None,
                         formulation: str = DEFAULT_FORMULATION, hertz: str = "plane_strain",
                         n_positions: int = DEFAULT_POSITIONS, crack_mesh: CrackMesh | None = None,
                         cache_dir=USER_CACHE, healthy: MeshStiffness | None = None) -> CrackPairStiffness:
    """Healthy and cracked single-pair stiffness of ``pair`` along its path of contact.

    Parameters
    ----------
    pair : GearPair
    depth, angle, start_tangent, start_radius
        The crack (:func:`flexgear.fe.crack.root_crack`), placed on tooth 0's left fillet.
    load : float
        Normal load [N] (the Hertz term depends on it).
    cracked : {1, 2}
        Gear of the pair that carries the crack (2: the ring of a planet-ring pair).
    settings, material, formulation, hertz, n_positions, cache_dir
        As :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh`.
    crack_mesh : CrackMesh, optional
        Refinement at the crack tip.
    healthy : MeshStiffness, optional
        A healthy :func:`loaded_mesh` result of the same pair and options (reused).

    Returns
    -------
    CrackPairStiffness
    """
    if cracked not in (1, 2):
        raise ConfigError(f"cracked = {cracked!r}: must be 1 or 2 (the gear of pair {pair.name})")
    material = Material() if material is None else material
    settings = MeshSettings() if settings is None else settings
    gear = pair.g1 if cracked == 1 else pair.g2
    crack = root_crack(gear, depth, angle, start_tangent=start_tangent, start_radius=start_radius)
    kw = dict(material=material, formulation=formulation, hertz=hertz, n_positions=n_positions)
    if healthy is None:
        healthy = loaded_mesh(pair, load, settings=settings, cache_dir=cache_dir, **kw)
    tc_h = healthy.c1 if cracked == 1 else healthy.c2
    model, gm = cracked_gear_model(gear, crack, settings, material, formulation, cache_dir, crack_mesh)
    tc_c = tooth_compliance(gear, tc_h.radius, model=model, material=material, neighbours=tc_h.reach)
    tables = (tc_c, healthy.c2) if cracked == 1 else (healthy.c1, tc_c)
    ms_c = loaded_mesh(pair, load, compliances=tables, **kw)
    info = {"ndofs": model.ndofs, "h_crack_tip": gm.info.get("h_crack_tip"),
            "h_tooth": gm.info.get("h_tooth"), "level": settings.level}
    return CrackPairStiffness(pair=pair, cracked=cracked, crack=crack, load=float(load),
                              roll=roll_angle(gear, tc_h.radius), k_healthy=healthy.k_single,
                              k_cracked=ms_c.k_single, delta_c=tc_c.bulk - tc_h.bulk,
                              healthy=healthy, cracked_mesh=ms_c, info=info)


#: Format of the cache entries of :func:`crack_ratio_table` and :func:`crack_series_table` (bump when their meaning changes).
CRACK_RATIO_FORMAT = 1


def _crack_table_entry(pair, depth, angle, load, cracked, settings, formulation, material, cache_dir, kind):
    """(key, npz, side, folder, digest) of a cached FE crack table of ``kind`` (its cache folder)."""
    from ..fe import crack as fe_crack
    from . import compliance, loaded_mesh as lm_module

    code = hashlib.sha256()
    for mod in (fe_crack, compliance, lm_module):
        code.update(Path(mod.__file__).read_bytes())
    code.update(Path(__file__).read_bytes())
    key = {"format": CRACK_RATIO_FORMAT, "gears": [gear_parameters(pair.g1), gear_parameters(pair.g2)],
           "cracked": int(cracked), "depth": float(depth), "angle": float(angle), "load": float(load),
           "level": int(settings.level), "order": int(settings.order), "formulation": formulation,
           "material": [float(material.E), float(material.nu), float(material.rho)], "code": code.hexdigest(),
           "numpy": np.__version__}
    key = json.loads(json.dumps(jsonable(key), sort_keys=True, separators=(",", ":")))
    digest = hashlib.sha256(json.dumps(key, sort_keys=True, separators=(",", ":")).encode()).hexdigest()
    folder = Path(cache_dir if cache_dir is not None else user_cache_dir()) / kind
    prefix = "ratio" if kind == "crack-ratio" else "pair"
    return key, folder / f"{prefix}-{digest}.npz", folder / f"{prefix}-{digest}.json", folder, f"{prefix}-{digest}"


def _cached_crack_table(pair, depth, angle, load, cracked, settings, formulation, material, cache_dir, kind,
                        compute) -> dict:
    """The arrays ``compute(cps)`` of :func:`crack_pair_stiffness` with the FE mesh ``settings``, cached in
    ``kind/`` of ``cache_dir`` (checksummed, written atomically under the entry's lock; an
    unusable entry is recomputed)."""
    material = Material() if material is None else material
    key, npz, side, folder, name = _crack_table_entry(pair, depth, angle, load, cracked, settings, formulation,
                                                      material, cache_dir, kind)
    with entry_lock(folder, name):
        if side.exists() or npz.exists():
            try:
                return read_cached_arrays(npz, side, key)
            except Exception as exc:  # noqa: BLE001 - any failure means: recompute
                log.warning("crack table cache %s unusable (%s); recomputing", npz.name, exc)
                discard_files(side, npz)
        cps = crack_pair_stiffness(pair, depth, angle, load, cracked=cracked, settings=settings,
                                   material=material, formulation=formulation)
        arrays = compute(cps)
        try:
            write_cached_arrays(npz, side, key, arrays)
        except OSError as exc:
            log.warning("crack table cache not written (%s)", exc)
    return arrays


def _on_path_sorted(cps, values: dict) -> dict:
    """``values`` (name -> array over the grid) and ``roll`` on the path, by increasing roll."""
    on = cps.on_path & np.isfinite(cps.ratio)
    order = np.argsort(cps.roll[on])
    return {"roll": cps.roll[on][order], **{k: v[on][order] for k, v in values.items()}}


def crack_ratio_table(pair, depth: float, angle: float, load: float, *, cracked: int = 1, level: int = 1,
                      formulation: str = DEFAULT_FORMULATION, material: Material | None = None,
                      cache_dir=None) -> tuple[np.ndarray, np.ndarray]:
    """(roll, ratio): the FE single-pair stiffness ratio k_cracked / k_healthy of ``pair`` with a
    root crack (``depth`` [m], ``angle`` [rad]) on gear ``cracked``, against the roll angle
    tan(alpha_y) of the cracked gear's contact (increasing, on the path), at the normal load
    ``load`` [N] (:func:`crack_pair_stiffness` at the FE mesh ``level``).

    Cached in ``crack-ratio/`` of ``cache_dir`` (default: the user cache), keyed by the gears, the
    crack, the load, the FE settings and material and the source of the modules that compute it;
    checksummed, written atomically under the entry's lock; an unusable entry is recomputed."""
    z = _cached_crack_table(pair, depth, angle, load, cracked, MeshSettings(level=level), formulation, material,
                            cache_dir, "crack-ratio", lambda cps: _on_path_sorted(cps, {"ratio": cps.ratio}))
    return z["roll"], z["ratio"]


def crack_series_table(pair, depth: float, angle: float, load: float, *, cracked: int = 1,
                       width_fraction: float = 1.0, settings: MeshSettings | None = None,
                       formulation: str = DEFAULT_FORMULATION, material: Material | None = None,
                       cache_dir=None) -> tuple[np.ndarray, np.ndarray]:
    """(roll, series): the extra compliance [m/N] of the pair of a tooth with a root crack over
    ``width_fraction`` of the face width, ``1 / k_partial - 1 / k_healthy`` with ``k_partial`` the
    slices in parallel of :func:`partial_width_stiffness`, against the roll angle tan(alpha_y) of
    the cracked gear's contact (increasing, on the path), from the FE single-pair stiffnesses of
    :func:`crack_pair_stiffness` at the normal load ``load`` [N] and FE mesh ``settings`` (default:
    :class:`~flexgear.fe.meshing.MeshSettings`'s). Through the
    face width (1) it is the cracked tooth's extra bulk compliance (the Hertz terms cancel) and
    does not depend on the load; over part of it, the Hertz term enters k_partial at ``load``.

    The series compliance of the compliant contact law (:mod:`flexgear.dynamics.model.tooth_laws`).
    The pair FE is cached in ``crack-pair/`` of ``cache_dir`` (default: the user cache) as
    :func:`crack_ratio_table`'s."""
    settings = MeshSettings() if settings is None else settings
    z = _cached_crack_table(pair, depth, angle, load, cracked, settings, formulation, material, cache_dir,
                            "crack-pair", lambda cps: _on_path_sorted(cps, {"k_healthy": cps.k_healthy,
                                                                            "k_cracked": cps.k_cracked}))
    k_p = partial_width_stiffness(z["k_healthy"], z["k_cracked"], width_fraction)
    return z["roll"], 1.0 / k_p - 1.0 / z["k_healthy"]


def partial_width_stiffness(k_healthy, k_cracked, fraction: float):
    """Single-pair stiffness [N/m] with a crack over ``fraction`` of the face width.

        Slices in parallel (Chen & Shao 2011): ``k = fraction k_cracked + (1 - fraction) k_healthy``.
        This ignores the shear by which the healthy width carries load over to the cracked part, so
        a 3D sector is stiffer (:mod:`flexgear.stiffness.crack3d`).
    """
    f = float(fraction)
    if not 0.0 <= f <= 1.0:
        raise ConfigError(f"face-width fraction = {fraction!r}: must lie in [0, 1] (1 = through crack)")
    return f * np.asarray(k_cracked) + (1.0 - f) * np.asarray(k_healthy)


# ============================================================================================
# rigid-model representations
# ============================================================================================
@dataclass
class RigidCrackErrors:
    """Errors of the rigid-model representations of a crack against the FE.

        Each error is the representation's k_cracked / k_healthy over the FE's, minus 1, at the
        loads ``loads`` [N] (rows) and roll angles ``roll`` (columns).

        Attributes
        ----------
        loads : ndarray (L,)
        roll : ndarray (J,)
        fe_ratio : ndarray (L, J)
            FE k_cracked / k_healthy.
        law_constant, law_table : ndarray (L, J)
            Per-tooth contact-law factor: one number (kappa^(1/e) the FE ratio's mean at the
            reference load), or tabulated against the roll angle.
        series : dict[str, ndarray (L, J)]
            Series compliance delta_c(roll) added to the rigid law F = K delta^e, per law name.
        laws : dict[str, tuple(K, e)]
        reference : float
            Load the tables were taken at [N].
    """

    loads: np.ndarray
    roll: np.ndarray
    fe_ratio: np.ndarray
    law_constant: np.ndarray
    law_table: np.ndarray
    series: dict
    laws: dict
    reference: float

    def summary(self) -> dict:
        """{representation: (max |error|, RMS error)} over loads and path [-]."""
        out = {"contact law, one factor": self.law_constant, "contact law, roll table": self.law_table}
        out.update({f"series compliance, {k}": v for k, v in self.series.items()})
        return {k: (float(np.max(np.abs(v))), float(np.sqrt(np.mean(v * v)))) for k, v in out.items()}


def rigid_crack_errors(cps: CrackPairStiffness, laws: dict, loads) -> RigidCrackErrors:
    """Errors of the rigid representations of the crack of ``cps`` (see :class:`RigidCrackErrors`).

        Parameters
        ----------
        cps : CrackPairStiffness
            FE result; its load is the reference load of the tables.
        laws : dict[str, tuple(K, e)]
            Rigid IMPACT laws F = K delta^e [N/m^e, -] for the series representation.
        loads : array_like
            Loads [N] at which the representations are judged.

        Notes
        -----
        A law factor kappa gives the stiffness ratio kappa^(1/e) at every load; the series
        compliance gives 1 / (1 + delta_c k_rigid(F)), k_rigid = K^(1/e) F^(1 - 1/e).
    """
    loads = np.atleast_1d(np.asarray(loads, float))
    on = cps.on_path
    dc = cps.delta_c[on]
    ratio_ref = cps.ratio[on]
    fe = np.array([(lambda h, c: (c / h)[on])(*cps.at_load(float(F))) for F in loads])
    const = float(np.mean(ratio_ref))
    law_constant = const / fe - 1.0
    law_table = ratio_ref[None, :] / fe - 1.0
    series = {}
    for name, (K, e) in laws.items():
        k_rig = K ** (1.0 / e) * loads ** (1.0 - 1.0 / e)
        series[name] = 1.0 / (1.0 + dc[None, :] * k_rig[:, None]) / fe - 1.0
    return RigidCrackErrors(loads=loads, roll=cps.roll[on], fe_ratio=fe, law_constant=law_constant,
                            law_table=law_table, series=series, laws=dict(laws), reference=cps.load)


def fitted_law(healthy: MeshStiffness, loads, exponent: float | None = None) -> tuple[float, float]:
    """(K, e) of the IMPACT law fitted to the healthy FE mean transmission error at ``loads``
    (:func:`flexgear.stiffness.impact_fit.fit_impact_to_te`, reusing ``healthy``'s tables)."""
    loads = np.asarray(loads, float)
    te = []
    for F in loads:
        ms = loaded_mesh(healthy.pair, float(F), compliances=(healthy.c1, healthy.c2),
                         formulation=healthy.c1.formulation, hertz=healthy.hertz,
                         n_positions=healthy.grid.n)
        te.append(zone_mean_te(ms))
    return fit_impact_to_te(loads, np.array(te), healthy.grid.eps_alpha, exponent)


# ============================================================================================
# convergence
# ============================================================================================
@dataclass
class CrackConvergence:
    """Cracked and healthy tooth compliance of one gear over mesh levels.

    Attributes
    ----------
    levels : ndarray (L,)
    h : ndarray (L,)
        Tooth element size h_tooth [m] (the crack tip size is proportional to it).
    h_tip : ndarray (L,)
        Element size at the crack tip [m].
    radius : ndarray (R,)
        Contact radii [m].
    cracked, healthy : ndarray (L, R)
        Bulk tooth compliance [m/N].
    ndofs : ndarray (L,)
        Degrees of freedom of the cracked model.
    rich, rich_delta : RichardsonResult
        Of the cracked compliance and of the crack's extra compliance ``cracked - healthy``.
    """

    levels: np.ndarray
    h: np.ndarray
    h_tip: np.ndarray
    radius: np.ndarray
    cracked: np.ndarray
    healthy: np.ndarray
    ndofs: np.ndarray
    rich: RichardsonResult
    rich_delta: RichardsonResult


def crack_convergence(gear, depth: float, angle: float, levels, radii, *, material=None,
                      formulation: str = DEFAULT_FORMULATION, crack_mesh: CrackMesh | None = None,
                      cache_dir=USER_CACHE, log=None) -> CrackConvergence:
    """Compliance at ``radii`` of the cracked gear refined over ``levels`` (crack tip refined with the tooth).

        Parameters
        ----------
        gear : SpurGear
        depth, angle : float
            The crack (tooth 0, left fillet, 30 deg start) [m, rad].
        levels : sequence of int
            At least three increasing mesh levels.
        radii : array_like
            Contact radii on the involute [m].
        log : callable, optional
            ``log(str)`` progress messages.
    """
    levels = [int(v) for v in levels]
    if len(levels) < 3 or any(b <= a for a, b in zip(levels, levels[1:])):
        raise ConfigError(f"levels = {levels}: need >= 3 strictly increasing refinement levels")
    material = Material() if material is None else material
    crack = root_crack(gear, depth, angle)
    radii = np.atleast_1d(np.asarray(radii, float))
    C, Hc, H, Ht, N = [], [], [], [], []
    for lv in levels:
        st = MeshSettings(level=lv)
        model, gm = cracked_gear_model(gear, crack, st, material, formulation, cache_dir, crack_mesh)
        healthy = assemble(mesh_gear(gear, st, cache_dir=cache_dir), material, gear.face_width, formulation)
        C.append(tooth_compliance(gear, radii, model=model, neighbours=False).bulk)
        Hc.append(tooth_compliance(gear, radii, model=healthy, neighbours=False).bulk)
        H.append(gm.info["h_tooth"])
        Ht.append(gm.info["h_crack_tip"])
        N.append(model.ndofs)
        if log:
            log(f"{gear.name} level {lv}: {model.ndofs} dofs, h_tip = {Ht[-1]*1e6:.3g} um, cracked "
                f"{np.array2string(C[-1], precision=5)} m/N")
    C, Hc, H = np.array(C), np.array(Hc), np.array(H)
    return CrackConvergence(levels=np.array(levels), h=H, h_tip=np.array(Ht), radius=radii, cracked=C,
                            healthy=Hc, ndofs=np.array(N), rich=richardson(C, h=H),
                            rich_delta=richardson(C - Hc, h=H))


def main(argv=None) -> int:
    """``python -m flexgear.stiffness.crack``: single-pair stiffness of a pair with a root crack in
    one tooth against depth, the potential-energy model, and the rigid-model representations."""
    import argparse
    import math

    from ..config import load_config
    from .crack_energy import crack_tip_in_beam, pe_pair_stiffness

    ap = argparse.ArgumentParser(prog="python -m flexgear.stiffness.crack", description=main.__doc__)
    ap.add_argument("--preset", default="spur_pair")
    ap.add_argument("--pair", default=None, help="pair name (default: the preset's first)")
    ap.add_argument("--cracked", type=int, default=1, choices=(1, 2), help="gear of the pair with the crack")
    ap.add_argument("--depths", type=float, nargs="+", default=[0.5e-3, 1.0e-3, 1.5e-3, 2.0e-3],
                    help="crack lengths [m]")
    ap.add_argument("--angle-deg", type=float, default=45.0)
    ap.add_argument("--level", type=int, default=2)
    ap.add_argument("--formulation", default=DEFAULT_FORMULATION, choices=("plane_stress", "plane_strain"))
    ap.add_argument("--torque", type=float, default=200.0, help="torque on gear 2 [N m] (load = torque / r_b2)")
    a = ap.parse_args(argv)
    cfg = load_config(a.preset)
    pair = cfg.pairs[a.pair] if a.pair else next(iter(cfg.pairs.values()))
    load = a.torque / pair.g2.rb
    law = cfg.contact_law(pair)
    paper = (law.K, law.e)
    settings = MeshSettings(level=a.level)
    healthy, fit = None, None
    print(f"pair {pair.name}, crack in {'g1' if a.cracked == 1 else 'g2'}, angle {a.angle_deg:g} deg, "
          f"start at the 30 deg tangent, load {load:.5g} N, level {a.level}, {a.formulation}")
    for q in a.depths:
        cps = crack_pair_stiffness(pair, q, math.radians(a.angle_deg), load, cracked=a.cracked,
                                   settings=settings, material=cfg.material, formulation=a.formulation,
                                   healthy=healthy)
        healthy = cps.healthy
        on = cps.on_path
        if fit is None:
            fit = fitted_law(healthy, load * np.array([0.5, 1.0, 1.5]))
        g = pair.g1 if a.cracked == 1 else pair.g2
        tip = crack_tip_in_beam(g, cps.crack)
        grid = healthy.grid
        pe = [pe_pair_stiffness(pair, grid.r1[on], grid.r2[on], cfg.material, a.formulation, t, a.cracked)
              for t in (None, tip)]
        ratio_pe = pe[1] / pe[0]
        ratio = cps.ratio[on]
        print(f"\ndepth {q*1e3:g} mm (tip {cps.info['h_crack_tip']*1e6:.3g} um elements, {cps.info['ndofs']} dofs)")
        print("  roll [rad]   k_healthy [N/m]  k_cracked [N/m]  ratio FE  ratio PE  delta_c [m/N]")
        for j in np.linspace(0, np.count_nonzero(on) - 1, 7).astype(int):
            print(f"  {cps.roll[on][j]:9.4f}   {cps.k_healthy[on][j]:.5e}      {cps.k_cracked[on][j]:.5e}"
                  f"      {ratio[j]:.4f}    {ratio_pe[j]:.4f}   {cps.delta_c[on][j]:.4e}")
        laws = {"FE-fitted law K = %.4g N/m^%.3g" % fit: fit}
        laws["preset law K = %.4g N/m^%.3g" % paper] = paper
        err = rigid_crack_errors(cps, laws, load * np.array([0.5, 1.0, 2.0]))
        print("  rigid representations, error of k_cracked/k_healthy over the path at 0.5, 1, 2 x load:")
        for name, (mx, rms) in err.summary().items():
            print(f"    {name:55s} max {mx*100:6.2f} %   RMS {rms*100:6.2f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
