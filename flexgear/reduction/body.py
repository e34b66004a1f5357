"""The reduced body: reduced matrices, the basis that maps them back, residual flexibility.

Coordinates ``q = [q_b, eta]``: first the interface coordinates ``q_b`` (for a
:class:`~flexgear.reduction.interface.RigidInterface` the frame's ``u_x, u_y`` [m] and
``theta`` [rad]), then the modal coordinates ``eta`` of the fixed-interface modes
(mass-normalised, [sqrt(kg) m]). The full displacement is ``u = V q`` (+ the residual static
deflection of the contact loads, :meth:`ReducedBody.reconstruct`).

For a rigid interface with nothing else held, ``V = [R, Phi]`` with ``R`` the rigid motions:
``K_r = diag(0, 0, 0, omega_1^2, ...)`` and ``M_r = [[m_rigid, R^T M Phi], [Phi^T M R, I]]``,
whose off-diagonal block is the inertia coupling between the frame's motion and the modes
(the planar floating-frame terms that the solver linearises about the frame).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError


@dataclass
class ReducedBody:
    """A linear elastic body reduced to a few coordinates.

    Attributes
    ----------
    K : ndarray (n, n)
        Reduced stiffness ``V^T K V`` [N/m, N, N m per coordinate units].
    M : ndarray (n, n)
        Reduced mass ``V^T M V`` [kg, kg m, kg m^2 per coordinate units].
    basis : ndarray (ndofs, n)
        Reduction basis V: columns = constraint modes, then fixed-interface modes.
    n_interface : int
        Number of interface coordinates (the first ones).
    frequencies : ndarray (n_modes,)
        Fixed-interface natural frequencies [Hz] (empty for a static reduction).
    names : tuple of str
        Coordinate names.
    model : FEModel
        The full model (for output and stresses).
    interface : InterfaceMap
    residual : ResidualFlexibility or None
        Static flexibility of the modes left out (see :mod:`flexgear.reduction.residual`).
    method : str
        ``"guyan"`` or ``"craig_bampton"``.
    info : dict
        Timings and sizes.
    """

    K: np.ndarray
    M: np.ndarray
    basis: np.ndarray
    n_interface: int
    frequencies: np.ndarray
    names: tuple
    model: object
    interface: object
    residual: object = None
    method: str = ""
    info: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of reduced coordinates."""
        return self.K.shape[0]

    @property
    def n_modes(self) -> int:
        """Number of fixed-interface modes."""
        return self.n - self.n_interface

    @property
    def modal_stiffness(self) -> np.ndarray:
        """Diagonal of the modal block of K, omega_k^2 [1/s^2]."""
        return np.diag(self.K)[self.n_interface:].copy()

    def _check_q(self, q):
        q = np.asarray(q, dtype=float)
        if q.shape[0] != self.n:
            raise ConfigError(f"q.shape = {q.shape}: first dimension must equal the "
                              f"{self.n} reduced coordinates")
        return q

    def reconstruct(self, q, loads=None) -> np.ndarray:
        """Full displacement vector from reduced coordinates [m].

        Parameters
        ----------
        q : ndarray (n,) or (n, k)
            Reduced coordinates.
        loads : ndarray (ndofs,) or (ndofs, k), optional
            External nodal loads acting at that instant (contact forces) [N]; their residual
            static deflection (the quasi-static part of the modes left out) is added.

        Returns
        -------
        ndarray (ndofs,) or (ndofs, k)
            Dof vector; ``model.nodal_field(u)`` gives nodal values (n_nodes, 2).
        """
        q = self._check_q(q)
        u = self.basis @ q
        if loads is not None:
            if self.residual is None:
                raise ConfigError("loads given but the body carries no residual flexibility")
            u = u + self.residual.apply(loads)
        return u

    def reduce_load(self, f) -> np.ndarray:
        """Generalised force ``V^T f`` of a full nodal load ``f`` [N] -> reduced coordinates."""
        f = np.asarray(f, float)
        if f.shape[0] != self.basis.shape[0]:
            raise ConfigError(f"f.shape = {f.shape}: first dimension must equal ndofs = "
                              f"{self.basis.shape[0]}")
        return self.basis.T @ f

    def inertia_invariants(self) -> dict:
        """Mass invariants of the planar floating frame (modes expressed in the body frame).

                With ``R = [e_x, e_y, e_theta]`` the rigid motions about the frame origin, ``Phi`` the
                modal columns and ``E`` the 90-degree turn of every nodal vector::

                    mass    m = e_x^T M e_x [kg]            J = e_theta^T M e_theta [kg m^2]
                    first   c = [e_x, e_y]^T M e_theta      (frame origin at the centre of mass: 0) [kg m]
                    S_t = [e_x, e_y]^T M Phi  (2, n)        translation-mode coupling
                    S_r = e_theta^T M Phi     (n,)          rotation-mode coupling
                    G   = Phi^T M E Phi       (n, n)        gyroscopic (skew) coupling of the modes

                Returns
                -------
                dict with keys ``m, J, c, S_t, S_r, G``.
        """
        model = self.model
        R = model.rigid_body_modes()
        c0 = self.interface.centre if self.interface is not None else (0.0, 0.0)
        R[:, 2] += c0[1] * R[:, 0] - c0[0] * R[:, 1]
        Phi = self.basis[:, self.n_interface:]
        MR = model.M @ R
        EPhi = np.zeros_like(Phi)
        EPhi[model.node_dofs[:, 0]] = -Phi[model.node_dofs[:, 1]]
        EPhi[model.node_dofs[:, 1]] = Phi[model.node_dofs[:, 0]]
        return {"m": float(R[:, 0] @ MR[:, 0]), "J": float(R[:, 2] @ MR[:, 2]),
                "c": MR[:, :2].T @ R[:, 2], "S_t": MR[:, :2].T @ Phi, "S_r": MR[:, 2] @ Phi,
                "G": Phi.T @ (model.M @ EPhi)}

    def strain_energy(self, q) -> float:
        """``q^T K_r q / 2`` [J]."""
        q = self._check_q(q)
        return 0.5 * float(q @ (self.K @ q))


class LazyBasisBody(ReducedBody):
    """A :class:`ReducedBody` whose ``basis`` is read on first use.

    ``basis`` may be given as a callable returning the array (a body loaded from the cache:
    the simulation needs only the reduced matrices and the flank tables, so the basis, the
    largest array by far, 100,884 x 166 numbers on the MERCURY ring, is read when a field is
    reconstructed or a new load reduced).
    """

    @property
    def basis(self) -> np.ndarray:
        b = self.__dict__["_basis"]
        if callable(b):
            b = np.asarray(b())
            self.__dict__["_basis"] = b
        return b

    @basis.setter
    def basis(self, value):
        self.__dict__["_basis"] = value
