"""MERCURY 1-A: planet-ring force and sun torque
=============================================

MERCURY 1-A: the planet1-ring vertical force, and the sun torque against statics.

This is the README's Python example. With the ring fixed, the carrier turns at
f_c = f_sun z_s / (z_s + z_r) and the sun needs T_sun = T_carrier z_s / (z_s + z_r).
"""
import flexgear

cfg = flexgear.load_config("mercury_1a")  # or a path to a TOML file
cfg.simulation["duration"] = 0.5
res = flexgear.run(cfg)                   # flexgear.results.Result
fy = res.meshes["planet1-ring"].force_global[:, 1]   # vertical force, N
sun_torque = res.bodies["sun"].torque.mean()         # N m, to hold the sun speed

if __name__ == "__main__":
    from flexgear.results.plots import fig_mesh_spectrum

    print(f"mean sun torque {sun_torque:.3f} N m")
    fig_mesh_spectrum(res, "planet1-ring").savefig("ex04_planetary_spectrum.png", dpi=300)
