"""Friction losses and mesh efficiency of a pair with the load sharing of its quasi-static
loaded mesh (:func:`flexgear.stiffness.loaded_mesh.loaded_mesh`): the friction power
mu F_k |v_s,k| of every loaded tooth pair, summed and averaged over the mesh cycle
(:func:`flexgear.gears.lubrication.path_losses`). With the FE load sharing in place of the
equal sharing of the tooth loss factor H_V, this is the numerical loss factor of Wimmer
(FVA 2006) for a constant coefficient, and the mesh efficiency for any coefficient model.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..gears.lubrication import PathLosses, path_losses
from .loaded_mesh import ON_PATH, MeshStiffness


def mesh_losses(mesh: MeshStiffness, coefficient, omega1: float) -> PathLosses:
    """Friction losses of ``mesh`` with gear 1 turning at ``omega1`` [rad/s].

    Parameters
    ----------
    mesh : MeshStiffness
        A loaded mesh on the path of contact (``extended=False``): its positions ``s`` over one
        base pitch from the start of the usable path, and the pair loads at s + k p_b.
    coefficient : callable
        ``coefficient(v_s, u_e, load_per_width, R)`` -> mu (e.g.
        :meth:`flexgear.gears.tribology.FrictionLaw.coefficient`).
    omega1 : float
        Angular velocity of gear 1 [rad/s].
    """
    if np.any(mesh.grid.tip != ON_PATH):
        raise ConfigError(f"pair {mesh.pair.name}: mesh losses need the loaded mesh on the path of contact "
                          "(loaded_mesh(..., extended=False)); contacts outside it have no involute sliding speed")
    return path_losses(mesh.pair, mesh.s, mesh.pair_loads, mesh.load, omega1, coefficient)
