"""Spur pair: tooth friction and the oil film at two oil temperatures
==================================================================

The paper's spur pair with tooth friction (Xu et al. 2007) and an ISO VG 100 gear oil, the
preset ``spur_pair_friction``, run as its lumped model (``NAME:lumped``) at an oil temperature
of 40 and of 90 degC.

Each tooth pair's friction force acts along the flank tangent and reverses where the pair
crosses the pitch point, once per mesh period. The hotter oil is thinner: Dowson & Higginson's
minimum film grows as (eta u_e)^0.70 at a given load, so at the same speeds the two runs' films
differ by the factor (eta_90 / eta_40)^0.70. The film is thinner than the flanks' composite
roughness (lambda < 1: boundary lubrication by the lubrication guide's classes, 1 to 3 mixed),
where Xu et al.'s coefficient takes the roughness through its term in the RMS roughness S; with
it the hotter, thinner oil gives the lower coefficient (the friction models do not agree on
the sign of a temperature comparison: the lubrication guide).
"""
import dataclasses

import numpy as np

import flexgear
from flexgear.gears.lubrication import Lubricant
from flexgear.results.friction_plot import pitch_crossings

base = flexgear.load_config("spur_pair_friction:lumped").use_damping_ratio(0.05)
base.simulation.update(run_in=0.1, duration=0.25)   # s; 60 mesh periods kept
oil = base.lubrication.lubricant                    # VG 100 at the preset's 70 degC

runs, viscosity = {}, {}
for t_oil in (40.0, 90.0):                          # degC
    hot = Lubricant.from_iso_vg(100, t_oil, oil.density, oil.pressure_viscosity)
    cfg = dataclasses.replace(base, lubrication=dataclasses.replace(base.lubrication, lubricant=hot))
    runs[t_oil], viscosity[t_oil] = flexgear.run(cfg), hot.viscosity   # Pa s

mesh = {t: r.meshes["pinion-wheel"] for t, r in runs.items()}
efficiency = {t: m.attrs["mesh_efficiency"] for t, m in mesh.items()}
# film ratio of the two runs, contact by contact (same speeds, nearly the same loads)
film_ratio = np.nanmedian(mesh[90.0].film_minimum / mesh[40.0].film_minimum)
film_ratio_expected = (viscosity[90.0] / viscosity[40.0]) ** 0.70
crossings = pitch_crossings(runs[40.0], "pinion-wheel")   # s, each pair at the pitch point

if __name__ == "__main__":
    from flexgear.results.friction_plot import fig_friction
    from flexgear.style import figure, paper_style

    for t, m in mesh.items():
        print(f"{t:4.0f} degC: eta {1e3 * viscosity[t]:6.2f} mPa s, mesh efficiency {100 * efficiency[t]:.2f} %, "
              f"friction loss {m.friction_power.mean():5.1f} W, least lambda {np.nanmin(m.film_ratio):.3f}")
    print(f"film ratio 90/40 degC {film_ratio:.4f}, (eta_90 / eta_40)^0.70 = {film_ratio_expected:.4f}")
    fig_friction(runs[40.0], "pinion-wheel").savefig("ex05_oil_film_friction.png", dpi=300)
    with paper_style():
        fig = figure(3.5, 2.6)
        ax = fig.add_subplot()
        for t, m in mesh.items():
            on = np.isfinite(m.contact_position) & np.isfinite(m.film_minimum)
            ax.plot(1e3 * m.contact_position[on], 1e9 * m.film_minimum[on], ".", ms=1.5, label=f"{t:.0f} degC")
        ax.set_xlabel("contact position from the pitch point (mm)")
        ax.set_ylabel("minimum film thickness (nm)")
        ax.legend(markerscale=4)
        fig.savefig("ex05_oil_film_thickness.png", dpi=300)
