"""The coupled housing in the modal analysis (``flexgear modal`` with ``[housing] coupled = true``).

The gear set is linearised on its supports to ground (:func:`~.linearise.linearise`); the housing
then takes ground's place: its Craig-Bampton coordinates join the system, and each support of a
body the housing carries (:attr:`~flexgear.dynamics.model.housing.HousingCoupling.links`) acts
between the body and its anchor ``G q_h`` instead of ground, as in the solver
(:mod:`flexgear.dynamics.integrator.housing`). Exact to first order: the bearings are linear and
the housing's static deflection moves the gear set rigidly, so the meshes' operating point (and
their mean stiffness) is the one of the set on ground.
"""
from __future__ import annotations

import numpy as np

from ...errors import ConfigError
from .system import LinearSystem, Spring

#: name of the housing's body in a coupled LinearSystem (its coordinates are ``body_modes["housing"]``)
HOUSING = "housing"


def _anchor_rows(system: LinearSystem, coupling, names: list) -> dict:
    """Spring name -> the (n_h,) anchor row that replaces ground for that support spring."""
    out = {}
    for i, G in coupling.links:
        body = names[i]
        for d, axis in enumerate(("x", "y")):
            out[f"{body} bearing {axis}"] = G[d]
        out[f"{body} torsion"] = G[2]
    missing = [b for b in {names[i] for i, _ in coupling.links}
               if f"{b} bearing x" not in {s.name for s in system.springs}]
    if missing:
        raise ConfigError(f"housing.coupled = true: the linearised set has no support spring of {missing} to seat "
                          "in the housing")
    return out


def couple_system(system: LinearSystem, model) -> LinearSystem:
    """``system`` (linearised without housing) with ``model.housing`` coupled in: the housing's
    coordinates appended, its reduced mass and stiffness, foot springs (kind ``support``) and the
    seated supports' springs acting against their anchors. The housing's own strain energy is
    the :data:`~.system.COUPLING` share; its kinetic energy is the body ``housing``'s. No cyclic
    symmetry is claimed (the feet break it): modes are unclassified."""
    h = model.housing
    if h is None:
        return system
    n0, nh = system.n, h.n
    n = n0 + nh
    pad = lambda v: np.concatenate([v, np.zeros(nh)])  # noqa: E731
    anchors = _anchor_rows(system, h, [b.name for b in model.bodies])
    springs = []
    for s in system.springs:
        g = pad(s.g)
        if s.name in anchors:
            g[n0:] = -anchors[s.name]
        springs.append(Spring(s.name, s.kind, s.k, g))
    red = h.reduction
    for k, p in enumerate(red.role("foot")):
        for d, axis in enumerate(("x", "y")):
            g = np.zeros(n)
            g[n0 + p.coordinates[d]] = 1.0
            springs.append(Spring(f"housing foot {k + 1} {axis}", "support", red.housing.foot_stiffness, g))
    bodies = {name: (m, inertia, np.hstack([J, np.zeros((3, nh))])) for name, (m, inertia, J) in system.bodies.items()}
    out = LinearSystem(dofs=list(system.dofs) + list(h.names), bodies=bodies, springs=springs, planets=system.planets,
                       planet_angles=system.planet_angles, central=system.central, attrs=dict(system.attrs),
                       body_modes={HOUSING: list(range(n0, n))})
    K = out.spring_stiffness
    K[n0:, n0:] += 0.5 * (red.body.K + red.body.K.T)
    M = out.rigid_mass
    M[n0:, n0:] += h.mass
    if system.mass is not None:
        M[:n0, :n0] = system.mass
    if system.stiffness is not None:
        K[:n0, :n0] += system.stiffness - system.spring_stiffness
    out.stiffness, out.mass = K, M
    out.attrs["housing"] = (f"coupled housing: {nh} Craig-Bampton coordinates, {len(h.links)} seated supports, "
                            f"{len(red.role('foot'))} feet on {red.housing.foot_stiffness:.3g} N/m")
    return out
