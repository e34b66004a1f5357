"""Residual flexibility: the static deflection of the fixed-interface modes left out.

With the interface held (``q_b = 0``) the exact static response to a load ``f`` is
``K_ii^-1 f`` (inner dofs). Expanded in all fixed-interface modes (M-orthonormal, ``Phi^T K_ii
Phi = Omega^2``)::

    K_ii^-1 = sum_k phi_k phi_k^T / omega_k^2
            = Phi_kept Omega_kept^-2 Phi_kept^T  +  G_res

so the residual flexibility ``G_res = K_ii^-1 - Phi_kept Omega_kept^-2 Phi_kept^T`` is exactly the
*quasi-static condensation* of every mode left out: a mode far above the frequencies that the
integrator resolves responds to a load ``f(t)`` as ``eta_k = phi_k^T f / omega_k^2`` (its inertia
and damping are negligible), and summing those responses gives ``G_res f``. Computing it needs
no further modes: one solve with the factorisation of ``K_ii`` already made for the eigen-solve
and one projection. ``G_res M Phi_kept = 0``: the residual deflection has no component along a
kept mode, so modal and residual parts never count the same deflection twice.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError


class ResidualFlexibility:
    """``G_res = K_ii^-1 - Phi Omega^-2 Phi^T`` applied to full nodal loads.

    Parameters
    ----------
    factor : ClampedFactorisation
        Factorised ``K_ii`` (interface and fixed dofs held).
    modes : ndarray (ndofs, n_modes), or a callable returning it
        Kept fixed-interface modes, mass-normalised, zero on held dofs (a callable is called on
        first use: a body loaded from the cache reads them only when a load needs them).
    omega2 : ndarray (n_modes,)
        Their eigenvalues omega_k^2 [1/s^2].
    """

    def __init__(self, factor, modes, omega2):
        self.factor = factor
        self.omega2 = np.asarray(omega2, float)
        if np.any(self.omega2 <= 0):
            raise ConfigError("ResidualFlexibility: need one positive omega^2 per mode")
        self._modes = None
        self._load_modes = None
        if callable(modes):  # loaded on first use (a body read from the cache)
            self._load_modes = modes
        else:
            self._set_modes(modes)

    def _set_modes(self, modes):
        modes = np.asarray(modes, float)
        if modes.ndim != 2 or modes.shape[1] != self.omega2.size:
            raise ConfigError("ResidualFlexibility: need one positive omega^2 per mode")
        self._modes = modes

    @property
    def modes(self) -> np.ndarray:
        """Kept fixed-interface modes (ndofs, n_modes)."""
        if self._modes is None:
            self._set_modes(self._load_modes())
            self._load_modes = None
        return self._modes

    @property
    def ndofs(self) -> int:
        return self.modes.shape[0]

    def modal_part(self, F) -> np.ndarray:
        """``Phi Omega^-2 Phi^T F`` [m]: static deflection carried by the kept modes."""
        F = np.asarray(F, float)
        return self.modes @ ((self.modes.T @ F) / (self.omega2 if F.ndim == 1
                                                    else self.omega2[:, None]))

    def static(self, F) -> np.ndarray:
        """``K_ii^-1 F`` [m]: full static deflection with the interface held."""
        return self.factor.solve(F)

    def apply(self, F) -> np.ndarray:
        """``G_res F`` [m] for nodal loads ``F`` (ndofs,) or (ndofs, k) [N]."""
        F = np.asarray(F, float)
        if F.shape[0] != self.ndofs:
            raise ConfigError(f"F.shape = {F.shape}: first dimension must equal ndofs = "
                              f"{self.ndofs}")
        return self.static(F) - self.modal_part(F)

    def compliance(self, F_out, F_in) -> np.ndarray:
        """Residual compliance ``F_out^T G_res F_in`` [m/N] between two sets of unit loads."""
        return np.asarray(F_out, float).T @ self.apply(F_in)
