"""Interfaces of a reduced body: which dofs the reduced coordinates prescribe, which are clamped.

An interface maps the interface coordinates to the boundary dofs, ``u_b = T q_b``, and may hold
further dofs at zero. :class:`NodalInterface` keeps every boundary dof (``T = I``, the classic
Guyan / Craig-Bampton boundary); :class:`RigidInterface` ties a node set rigidly to a body frame
(``u_x``, ``u_y`` [m], ``theta`` [rad]). :func:`gear_interface` ties an external gear's bore
(``"hub"``) to the frame, and the ring's whole outer rim (``support="rim"``, default: the support
of its tooth compliance in :mod:`flexgear.stiffness`, needing no bolt data) or ``n_bolts`` bolt
patches (``"bolts"``: the rim free to bend between them). See the theory page *Reduction and
residual tables*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError

RING_SUPPORTS = ("rim", "bolts")
#: Default number of bolts of a bolted ring.
DEFAULT_BOLTS = 12


@dataclass(frozen=True)
class InterfaceMap:
    """An interface resolved on one FE model.

    Attributes
    ----------
    boundary : ndarray (nb,) int
        Dofs prescribed by the interface coordinates.
    T : ndarray (nb, nq)
        ``u[boundary] = T q_b`` [m per coordinate unit].
    fixed : ndarray (nf,) int
        Further dofs held at zero.
    names : tuple of str
        Names of the ``nq`` coordinates.
    rigid : bool
        True if ``T`` is the rigid motion of the boundary nodes about ``centre`` (then, with
        nothing else fixed, the constraint modes are the rigid motions of the whole body).
    centre : tuple of float
        Frame origin [m] (rigid interfaces).
    sectors : int
        The support repeats after a turn of ``2 pi / sectors`` (e.g. the number of bolts);
        0 for a support that every rotation about the axis maps onto itself (bore, whole rim).
    """

    boundary: np.ndarray
    T: np.ndarray
    fixed: np.ndarray
    names: tuple
    rigid: bool = False
    centre: tuple = (0.0, 0.0)
    sectors: int = 0

    @property
    def n_coordinates(self) -> int:
        """Number of interface coordinates."""
        return self.T.shape[1]

    def key(self) -> dict:
        """Everything that identifies the interface (for cache keys)."""
        import hashlib

        h = hashlib.sha256()
        for a in (self.boundary, self.fixed):
            h.update(np.ascontiguousarray(a, np.int64).tobytes())
        h.update(np.round(np.ascontiguousarray(self.T, float), 15).tobytes())
        return {"sha256": h.hexdigest(), "names": list(self.names), "rigid": self.rigid,
                "centre": [float(c) for c in self.centre], "sectors": int(self.sectors)}

    def tooth_period(self, z: int) -> int:
        """Teeth after which the support, and so a tooth's residual compliance, repeats.

        1 for an axisymmetric support; ``z / gcd(z, sectors)`` otherwise (66 teeth on 12 bolts:
        11).
        """
        return 1 if not self.sectors else z // math.gcd(int(z), int(self.sectors))


def _check_dofs(model, dofs, what):
    d = np.unique(np.asarray(dofs, dtype=np.int64).ravel())
    if d.size and (d[0] < 0 or d[-1] >= model.ndofs):
        raise ConfigError(f"{what}: dof indices must lie in 0..{model.ndofs - 1}")
    return d


class NodalInterface:
    """Keep every dof in ``dofs`` as a reduced coordinate (``T = I``); hold ``fixed`` at zero.

    Parameters
    ----------
    dofs : array_like of int
        Boundary dofs (at least one).
    fixed : array_like of int, optional
        Dofs held at zero (must not overlap ``dofs``).
    """

    def __init__(self, dofs, fixed=()):
        self.dofs = np.asarray(dofs, dtype=np.int64).ravel()
        self.fixed = np.asarray(fixed, dtype=np.int64).ravel()

    def resolve(self, model) -> InterfaceMap:
        b = _check_dofs(model, self.dofs, "NodalInterface dofs")
        f = _check_dofs(model, self.fixed, "NodalInterface fixed")
        if b.size == 0:
            raise ConfigError("NodalInterface dofs = []: need at least one boundary dof")
        if np.intersect1d(b, f).size:
            raise ConfigError("NodalInterface: a dof cannot be both a boundary dof and fixed")
        names = tuple(f"u{d}" for d in b)
        return InterfaceMap(b, np.eye(b.size), f, names)


class RigidInterface:
    """Tie the nodes ``nodes`` rigidly to a body frame at ``centre`` (3 coordinates in 2D).

    Parameters
    ----------
    nodes : array_like of int
        Node indices of the tied set (at least two distinct positions, so that the rotation is
        defined).
    centre : (float, float)
        Frame origin [m]; the rotation coordinate turns about it.
    fixed : array_like of int, optional
        Further dofs held at zero.
    sectors : int
        Rotational symmetry of the tied set about the axis (``2 pi / sectors``; 0 =
        axisymmetric, the default, e.g. a bore).
    """

    names = ("ux", "uy", "theta")

    def __init__(self, nodes, centre=(0.0, 0.0), fixed=(), sectors: int = 0):
        self.nodes = np.unique(np.asarray(nodes, dtype=np.int64).ravel())
        self.centre = (float(centre[0]), float(centre[1]))
        self.fixed = np.asarray(fixed, dtype=np.int64).ravel()
        if isinstance(sectors, bool) or not isinstance(sectors, (int, np.integer)) or sectors < 0:
            raise ConfigError(f"sectors = {sectors!r}: must be an integer >= 0 (0: axisymmetric)")
        self.sectors = int(sectors)

    def resolve(self, model) -> InterfaceMap:
        nodes = self.nodes
        if nodes.size and (nodes[0] < 0 or nodes[-1] >= model.n_nodes):
            raise ConfigError(f"RigidInterface nodes: indices must lie in 0..{model.n_nodes - 1}")
        x = model.node_coords[nodes] if nodes.size else np.zeros((0, 2))
        span = float(np.ptp(x, axis=0).max()) if nodes.size else 0.0
        if nodes.size < 2 or not span > 0:
            raise ConfigError(f"RigidInterface nodes: {nodes.size} node(s) spanning {span:g} m; "
                              "a rigid tie needs at least two distinct node positions")
        f = _check_dofs(model, self.fixed, "RigidInterface fixed")
        dofs = model.nodal_dofs(nodes)  # (n, 2)
        b = dofs.ravel()
        order = np.argsort(b)
        dx, dy = x[:, 0] - self.centre[0], x[:, 1] - self.centre[1]
        T = np.zeros((nodes.size, 2, 3))
        T[:, 0, 0] = 1.0
        T[:, 1, 1] = 1.0
        T[:, 0, 2] = -dy
        T[:, 1, 2] = dx
        T = T.reshape(-1, 3)[order]
        b = b[order]
        if np.intersect1d(b, f).size:
            raise ConfigError("RigidInterface: a tied node's dof cannot also be fixed")
        return InterfaceMap(b, T, f, self.names, rigid=True, centre=self.centre,
                            sectors=self.sectors)


def bolt_nodes(model, n_bolts: int, bolt_circle: float, bolt_radius: float,
               first_angle: float = 0.0) -> np.ndarray:
    """Nodes within ``bolt_radius`` of ``n_bolts`` equally spaced bolt centres.

    Parameters
    ----------
    model : FEModel
    n_bolts : int
        Number of bolts (>= 3, so that the ring is held in every direction).
    bolt_circle : float
        Radius of the bolt circle [m].
    bolt_radius : float
        Radius of the region around each centre that the bolt holds [m].
    first_angle : float
        Polar angle of the first bolt [rad].

    Raises
    ------
    ConfigError
        A bolt that catches fewer than three nodes (refine the mesh or enlarge the radius).
    """
    if isinstance(n_bolts, bool) or not isinstance(n_bolts, (int, np.integer)) or n_bolts < 3:
        raise ConfigError(f"n_bolts = {n_bolts!r}: a bolted ring needs an integer >= 3 bolts")
    for name, v in (("bolt_circle", bolt_circle), ("bolt_radius", bolt_radius)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ConfigError(f"{name} = {v!r}: must be a finite length > 0 m")
    x = model.node_coords
    out = []
    for k in range(n_bolts):
        a = first_angle + 2.0 * math.pi * k / n_bolts
        c = bolt_circle * np.array([math.cos(a), math.sin(a)])
        sel = np.flatnonzero(np.hypot(*(x - c).T) <= bolt_radius)
        if sel.size < 3:
            raise ConfigError(
                f"bolt {k} at ({c[0]*1e3:.4g}, {c[1]*1e3:.4g}) mm holds {sel.size} node(s) within "
                f"bolt_radius = {bolt_radius*1e3:.4g} mm: need >= 3 (refine the mesh or enlarge "
                "bolt_radius)")
        out.append(sel)
    return np.unique(np.concatenate(out))


def gear_interface(model, gear, support: str = "rim", n_bolts: int = DEFAULT_BOLTS,
                   bolt_circle: float | None = None, bolt_radius: float | None = None
                   ) -> RigidInterface:
    """The interface of a gear body: bore tied to the frame, or the ring's support.

        Parameters
        ----------
        model : FEModel
            Assembled from :func:`flexgear.fe.meshing.mesh_gear` (node sets ``"hub"`` / ``"rim"``).
        gear : SpurGear
        support : {"rim", "bolts"}
            Ring only: whole rim tied (default) or ``n_bolts`` bolts.
        n_bolts : int
            Bolts of a bolted ring (default 12).
        bolt_circle, bolt_radius : float, optional
            Bolt circle radius (default midway between root circle and rim) and radius held by each
            bolt (default a quarter of the rim thickness) [m].

        Returns
        -------
        RigidInterface
            Centred on the gear axis.
    """
    if not gear.internal:
        if "hub" not in model.node_sets:
            raise ConfigError(f"{gear.name}: the FE model has no bore (node set 'hub'); a "
                              "flexible external gear needs bore_diameter > 0")
        return RigidInterface(model.node_sets["hub"])
    if support not in RING_SUPPORTS:
        raise ConfigError(f"{gear.name}: support = {support!r}: must be one of {RING_SUPPORTS}")
    if support == "rim":
        if "rim" not in model.node_sets:
            raise ConfigError(f"{gear.name}: the FE model has no node set 'rim'")
        return RigidInterface(model.node_sets["rim"])
    r_rim = 0.5 * float(gear.rim_diameter)
    r_root = float(gear.rf)
    bc = 0.5 * (r_root + r_rim) if bolt_circle is None else bolt_circle
    br = 0.25 * (r_rim - r_root) if bolt_radius is None else bolt_radius
    if isinstance(bc, (int, float)) and not (r_root < bc < r_rim):
        raise ConfigError(f"{gear.name}: bolt_circle = {bc*1e3:.4g} mm must lie between the root "
                          f"circle ({r_root*1e3:.4g} mm) and the rim ({r_rim*1e3:.4g} mm)")
    return RigidInterface(bolt_nodes(model, n_bolts, bc, br), sectors=n_bolts)
