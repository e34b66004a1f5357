"""FE mesh stiffness against ISO 6336-1 (c', c_gamma) for a pair, its plot, and the command
``python -m flexgear.stiffness`` for the MERCURY 1-A pairs.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import numpy as np

from ..fe.meshing import USER_CACHE
from .compliance import DEFAULT_POSITIONS, HERTZ_MODES, roll_angle
from .loaded_mesh import MeshStiffness, loaded_mesh

# ============================================================================================
# ISO comparison
# ============================================================================================
@dataclass
class IsoComparison:
    """FE mesh stiffness against ISO 6336-1 for one pair (per face width, N/m^2).

    Attributes
    ----------
    name : str
    fe : MeshStiffness
    iso : flexgear.iso6336.PairStiffness
        ISO values with eps_alpha from the tip circles (ISO 21771, as ISO 6336 prescribes).
    iso_usable : flexgear.iso6336.PairStiffness
        ISO values with the contact ratio of the usable (involute) path the FE model uses.
    """

    name: str
    fe: MeshStiffness
    iso: object
    iso_usable: object

    @property
    def ratio_single(self) -> float:
        """FE max single-pair stiffness / ISO c' [-]."""
        return self.fe.c_single / self.iso.c_prime

    @property
    def ratio_mesh(self) -> float:
        """FE mean mesh stiffness / ISO c_gamma_alpha (tip-circle eps_alpha) [-]."""
        return self.fe.c_gamma / self.iso.c_gamma_alpha

    @property
    def ratio_mesh_usable(self) -> float:
        """FE mean mesh stiffness / ISO c_gamma_alpha with the usable-path eps_alpha [-]."""
        return self.fe.c_gamma / self.iso_usable.c_gamma_alpha

    def summary(self) -> str:
        """Text summary in ISO units."""
        from .iso6336 import to_iso_units as iso

        fe, i, u = self.fe, self.iso, self.iso_usable
        lines = [
            f"{self.name}: F = {fe.load/1e3:.4g} kN, eps_alpha = {i.eps_alpha:.3f} (tip circles), "
            f"{fe.grid.eps_alpha:.3f} (usable involute path, FE)",
            f"  c'      FE {iso(fe.c_single):6.2f}  ISO {iso(i.c_prime):6.2f} N/(mm um)"
            f"  FE/ISO {self.ratio_single:.3f}   (ISO c'_th {iso(i.single.c_th):.2f})",
            f"  c_gamma FE {iso(fe.c_gamma):6.2f}  ISO {iso(i.c_gamma_alpha):6.2f} N/(mm um)"
            f"  FE/ISO {self.ratio_mesh:.3f}   (ISO with usable eps: {iso(u.c_gamma_alpha):.2f}, "
            f"FE/ISO {self.ratio_mesh_usable:.3f})",
            f"  static TE mean {np.mean(fe.te)*1e6:.3f} um, peak-to-peak "
            f"{fe.te_peak_to_peak*1e6:.3f} um; pairs in contact {sorted(set(fe.n_pairs.tolist()))}",
        ]
        line_load = fe.load * math.cos(fe.pair.alpha_w) / fe.face_width  # F_t / b, K_A = 1
        if line_load < 1e5:
            low = (line_load / 1e5) ** 0.25
            lines.append(f"  note: F_t/b = {line_load/1e3:.3g} N/mm < 100 N/mm: ISO would reduce c' and "
                         f"c_gamma by ({line_load/1e3:.3g}/100)^0.25 = {low:.3f} (empirical low-load rule; "
                         f"not applied above)")
        lines += [f"  note: {n}" for n in fe.grid.notes]
        return "\n".join(lines)


def compare_iso(pair, load: float, name: str | None = None, **kw) -> IsoComparison:
    """Loaded-mesh FE stiffness of ``pair`` and ISO 6336-1 c', c_gamma_alpha for the same pair.

    Parameters
    ----------
    pair : GearPair
    load : float
        Normal tooth force [N].
    name : str, optional
    **kw
        Passed to :func:`~flexgear.stiffness.loaded_mesh.loaded_mesh`.
    """
    from .iso6336 import pair_stiffness

    g1, g2 = pair.g1, pair.g2
    b = min(g1.face_width, g2.face_width)
    fe = loaded_mesh(pair, load, **kw)

    def iso(eps):
        return pair_stiffness(g1.z, g2.z, g1.module, b, internal=pair.internal,
                              alpha=g1.pressure_angle, x1=g1.x, x2=g2.x, ha=g1.ha, hf=g1.hf,
                              eps_alpha=eps)

    return IsoComparison(name or pair.name, fe, iso(pair.contact_ratio), iso(fe.grid.eps_alpha))


def plot_mesh(results, path) -> None:
    """PNG of single-pair and mesh stiffness and static TE versus gear-1 roll angle."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .iso6336 import to_iso_units as iso

    fig, axs = plt.subplots(2, 1, figsize=(7, 7), sharex=False)
    for res in results:
        fe = res.fe
        g1 = fe.pair.g1
        xi = roll_angle(g1, fe.grid.r1)
        b = fe.face_width
        line, = axs[0].plot(np.degrees(xi), iso(fe.k_single / b), "--", label=f"{res.name} single pair")
        xi_m = roll_angle(g1, fe.grid.r1[: len(fe.s)])
        axs[0].plot(np.degrees(xi_m), iso(fe.k_mesh / b), "-", color=line.get_color(),
                    label=f"{res.name} mesh")
        axs[0].axhline(iso(res.iso.c_prime), color=line.get_color(), ls=":", lw=0.8)
        axs[0].axhline(iso(res.iso.c_gamma_alpha), color=line.get_color(), ls="-.", lw=0.8)
        axs[1].plot(np.degrees(xi_m), fe.te * 1e6, color=line.get_color(), label=res.name)
    axs[0].set_xlabel("roll angle of gear 1 at the contact [deg]")
    axs[0].set_ylabel("stiffness per face width [N/(mm um)]")
    axs[0].legend(fontsize=7)
    axs[0].set_title("FE + Hertz (lines) vs ISO 6336-1 c' (dotted), c_gamma (dash-dot)", fontsize=9)
    axs[1].set_xlabel("roll angle of gear 1, first pair [deg]")
    axs[1].set_ylabel("static transmission error [um]")
    axs[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def mercury_pairs(preset: str = "mercury_1a"):
    """The MERCURY 1-A sun-planet and planet-ring pairs and material from the preset."""
    from ..config import load_config

    cfg = load_config(preset)
    return cfg.pairs, cfg.material


def main(argv=None) -> int:
    """``python -m flexgear.stiffness``: FE/ISO stiffness ratios of the MERCURY 1-A pairs."""
    from ..fe.meshing import MeshSettings

    ap = argparse.ArgumentParser(prog="python -m flexgear.stiffness", description=main.__doc__)
    ap.add_argument("--level", type=int, default=2, help="mesh refinement level (default 2)")
    ap.add_argument("--order", type=int, default=2, help="element order 1 or 2 (default 2)")
    ap.add_argument("--load", type=float, default=None,
                    help="normal tooth force [N] (default: 200 N m / r_b of the planet = 10.14 kN)")
    ap.add_argument("--formulation", default="plane_stress", choices=("plane_stress", "plane_strain"))
    ap.add_argument("--hertz", default="plane_strain", choices=HERTZ_MODES)
    ap.add_argument("--positions", type=int, default=DEFAULT_POSITIONS)
    ap.add_argument("--plot", default=None, help="write a PNG of stiffness and TE vs roll angle")
    ap.add_argument("--cache-dir", default=None,
                    help="mesh cache directory (default: the per-user cache, $FLEXGEAR_CACHE_DIR/meshes or "
                    "~/.cache/flexgear/meshes)")
    a = ap.parse_args(argv)
    pairs, material = mercury_pairs()
    settings = MeshSettings(level=a.level, order=a.order)
    load = a.load if a.load is not None else 200.0 / pairs["sun-planet"].g2.rb
    out = []
    for name, pair in pairs.items():
        res = compare_iso(pair, load, name=name, settings=settings, material=material,
                          formulation=a.formulation, hertz=a.hertz, n_positions=a.positions,
                          cache_dir=a.cache_dir or USER_CACHE)
        print(res.summary())
        out.append(res)
    if a.plot:
        plot_mesh(out, a.plot)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

