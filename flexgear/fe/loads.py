"""Loads on FE gear models: tractions on boundary facets and smooth flank patch loads."""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError


def biweight(xi):
    """Biweight kernel (1 - xi^2)^2 on |xi| < 1, zero outside."""
    return np.clip(1.0 - xi * xi, 0.0, None) ** 2


def flank_patch_load(fb, rb: float, Sc: float, w: float, thickness: float, dim: int, what: str):
    """Load vector of a unit-resultant normal pressure patch on a flank.

    The pressure is a biweight in the involute arc length s (roll distance from the base
    circle) centred at ``Sc`` with half-width ``w`` [m], scaled so that its resultant over the
    facets of ``fb`` (thickness [m] in 2D, 1 in 3D) is 1 N, pointing into the body.
    """
    from skfem import Functional, LinearForm

    def pfun(x):
        s = (x[0] ** 2 + x[1] ** 2 - rb * rb) / (2.0 * rb) - Sc
        return biweight(s / w)

    tot = Functional(lambda v: pfun(v.x)).assemble(fb) * thickness
    if not tot > 0:
        raise ConfigError(f"{what}: the load patch has no support on the meshed flank")

    @LinearForm
    def load(v, wq):
        p = pfun(wq.x) / tot
        return -thickness * p * sum(wq.n[i] * v[i] for i in range(dim))

    return load.assemble(fb)


def traction_load(model, facets, traction) -> np.ndarray:
    """Consistent nodal forces of a boundary traction, ``f = t * int_Gamma tr . v ds``.

    Parameters
    ----------
    model : FEModel
    facets : str or ndarray
        A boundary name of ``model.mesh.boundaries`` or skfem facet indices.
    traction : callable
        ``traction(x, y) -> (tx, ty)`` [Pa] evaluated at quadrature points (arrays).

    Returns
    -------
    ndarray (ndofs,)
        Force vector [N] (thickness included).
    """
    from skfem import FacetBasis, LinearForm

    if isinstance(facets, str):
        facets = model.mesh.boundaries[facets]
    fb = FacetBasis(model.mesh, model.basis.elem, facets=facets, intorder=4)
    t = model.thickness

    @LinearForm
    def load(v, w):
        tx, ty = traction(w.x[0], w.x[1])
        return t * (tx * v[0] + ty * v[1])

    return load.assemble(fb)
