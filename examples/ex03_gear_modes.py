"""Clamped modes of a gear
=======================

Natural frequencies and mode shapes of the MERCURY 1-A sun gear, clamped at its bore.

The FE mass matrix carries the gear's mass: rho x face width x the area of the meshed outline.
Run as a script to write the mode-shape figure.
"""
import numpy as np

import flexgear
from flexgear.fe.elasticity import assemble, clamped_modes
from flexgear.fe.meshing import MeshSettings, mesh_gear

cfg = flexgear.load_config("mercury_1a")
gear = cfg.gears["sun"]
mesh = mesh_gear(gear, MeshSettings(level=1))
model = assemble(mesh, cfg.material, gear.face_width, "plane_stress")
freqs, shapes = clamped_modes(model, model.group_dofs("hub"), n_modes=6)    # Hz, (ndofs, 6)

# mass from the FE matrix: a rigid translation in x, u^T M u
ux = np.zeros(model.ndofs)
ux[0::2] = 1.0
fe_mass = float(ux @ (model.M @ ux))                         # kg


def polygon_area(xy):
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


outline_mass = (cfg.material.rho * gear.face_width
                * (polygon_area(gear.outline().points) - np.pi * (gear.bore_diameter / 2) ** 2))  # kg

if __name__ == "__main__":
    print("clamped-hub natural frequencies [kHz]:", np.round(freqs / 1e3, 2))
    print(f"mass: FE {fe_mass:.5f} kg, outline {outline_mass:.5f} kg")
    from flexgear.fe.output import modes_figure

    fig = modes_figure(mesh, model.nodal_field(shapes[:, :4]), freqs[:4], "sun, clamped bore")
    fig.savefig("ex03_gear_modes.png", dpi=150)
