"""Tooth-pair stiffness against ISO 6336
=====================================

Tooth-pair stiffness of the MERCURY 1-A sun-planet pair from plane FE plus Hertz contact,
against ISO 6336-1, at 10 kN along the line of action (200 N m on the planet; 500 N/mm of face
width): ISO's c' holds from 100 N/mm up, and MERCURY 1-A's own 237 N per mesh (12 N/mm) lies
below that range.

ISO's single-pair stiffness c' is its theoretical value c'_th times the empirical factor
C_M = 0.8 (measured over theoretical); a theoretical FE model must fall between the two.
A coarse mesh (level 0) keeps this example quick; ``python -m flexgear.stiffness --level 2``
gives the converged figures.
"""
import flexgear
from flexgear.fe.meshing import MeshSettings
from flexgear.stiffness.iso6336 import to_iso_units
from flexgear.stiffness.iso_comparison import compare_iso

cfg = flexgear.load_config("mercury_1a")
pair = cfg.pairs["sun-planet"]
load = 200.0 / cfg.gears["planet"].rb                       # N along the line of action (ISO's range)
cmp = compare_iso(pair, load, name="sun-planet", settings=MeshSettings(level=0),
                  material=cfg.material, n_positions=12)
c_single_fe = to_iso_units(cmp.fe.c_single)                 # N/(mm um)
c_prime_iso = to_iso_units(cmp.iso.c_prime)                 # N/(mm um), with C_M = 0.8
c_th_iso = to_iso_units(cmp.iso.single.c_th)                # N/(mm um), theoretical

if __name__ == "__main__":
    print(cmp.summary())
