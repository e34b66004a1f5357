"""FE mesh convergence of a gear: clamped frequencies and pitch-point tooth stiffness over mesh
levels, with Richardson extrapolation (:mod:`flexgear.fe.convergence`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..fe.meshing import USER_CACHE
from ..fe.convergence import RichardsonResult, richardson

@dataclass
class GearConvergence:
    """Clamped natural frequencies and pitch-point tooth stiffness of one gear on several levels.

    Attributes
    ----------
    name : str
        Gear name.
    levels : ndarray (L,) of int
        Mesh refinement levels, coarse to fine.
    h : ndarray (L,)
        Element size on the teeth, h_tooth [m].
    ndofs : ndarray (L,) of int
    freqs : ndarray (L, n_modes)
        Natural frequencies with the hub (external) or outer rim (ring) clamped [Hz].
    stiffness : ndarray (L,)
        Tooth stiffness at the pitch point, 1 / c_bulk [N/m] (see :mod:`flexgear.stiffness`).
    seconds : ndarray (L,)
        Wall time per level (mesh, assembly, eigen-solve, static solve) [s].
    freq_rich, stiff_rich : RichardsonResult
        Observed order, Richardson value and relative errors.
    clamp : str
        Boundary group held fixed.
    """

    name: str
    levels: np.ndarray
    h: np.ndarray
    ndofs: np.ndarray
    freqs: np.ndarray
    stiffness: np.ndarray
    seconds: np.ndarray
    freq_rich: RichardsonResult
    stiff_rich: RichardsonResult
    clamp: str

    def level_errors(self, level: int) -> tuple[float, float]:
        """(max relative frequency error over the modes, stiffness error) of ``level`` [-]."""
        i = int(np.flatnonzero(self.levels == level)[0])
        return float(np.max(self.freq_rich.rel_error[i])), float(self.stiff_rich.rel_error[i])

    def check(self, level: int, freq_tol: float = 0.01, stiff_tol: float = 0.02) -> bool:
        """True if ``level`` is within the tolerances of the Richardson values (and all orders
        are finite, i.e. the finest three levels converge monotonically)."""
        fe, se = self.level_errors(level)
        finite = bool(np.all(self.freq_rich.monotone) and np.all(self.stiff_rich.monotone))
        return finite and fe <= freq_tol and se <= stiff_tol


def gear_convergence(gear, levels, *, order: int = 2, n_modes: int = 10, material=None,
                     formulation: str = "plane_stress", cache_dir=USER_CACHE,
                     log=None) -> GearConvergence:
    """Refine the mesh of ``gear`` over ``levels`` and track modes and tooth stiffness.

    Parameters
    ----------
    gear : SpurGear
        External gears are clamped at the bore ("hub"), internal gears at the outer rim ("rim").
    levels : sequence of int
        At least three refinement levels (see :class:`flexgear.fe.meshing.MeshSettings`),
        increasing.
    order : int
        Element order (1 or 2).
    n_modes : int
        Number of clamped natural frequencies.
    material : Material, optional
    formulation : {"plane_stress", "plane_strain"}
    cache_dir : path or None
        Mesh cache directory; default the per-user cache (flexgear.fe.meshing.mesh_cache_dir), None: no cache.
    log : callable, optional
        ``log(str)`` progress messages.

    Returns
    -------
    GearConvergence
    """
    import time

    from ..fe.elasticity import clamped_modes
    from ..gears.material import Material
    from ..fe.meshing import MeshSettings
    from .compliance import clamp_group, pitch_point_compliance, tooth_fe_model

    levels = [int(v) for v in levels]
    if len(levels) < 3 or any(b <= a for a, b in zip(levels, levels[1:])):
        raise ConfigError(f"levels = {levels}: need >= 3 strictly increasing refinement levels")
    material = Material() if material is None else material
    clamp = clamp_group(gear)
    H, N, Fq, K, T = [], [], [], [], []
    for lv in levels:
        t0 = time.perf_counter()
        model, gm = tooth_fe_model(gear, MeshSettings(level=lv, order=order), material, formulation,
                                cache_dir)
        f, _ = clamped_modes(model, model.group_dofs(clamp), n_modes)
        c = pitch_point_compliance(gear, model=model)
        H.append(gm.info["h_tooth"])
        N.append(model.ndofs)
        Fq.append(f)
        K.append(1.0 / c)
        T.append(time.perf_counter() - t0)
        if log:
            log(f"{gear.name} level {lv}: {model.ndofs} dofs, f1 = {f[0]:.2f} Hz, "
                f"k_tooth = {1/c:.5g} N/m, {T[-1]:.1f} s")
    H = np.array(H)
    Fq, K = np.array(Fq), np.array(K)
    return GearConvergence(name=gear.name, levels=np.array(levels), h=H, ndofs=np.array(N),
                           freqs=Fq, stiffness=K, seconds=np.array(T),
                           freq_rich=richardson(Fq, h=H), stiff_rich=richardson(K, h=H),
                           clamp=clamp)
