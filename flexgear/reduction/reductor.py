"""Reductors: FE model + interface -> :class:`~flexgear.reduction.body.ReducedBody` (split as in pyMOR).

:class:`GuyanReductor` (static condensation, constraint modes ``Psi = [T; -K_ii^-1 K_ib T]``,
exact for loads on the interface) and :class:`CraigBamptonReductor` (plus fixed-interface modes
up to a cutoff or a count, optionally augmented). Both factorise ``K_ii`` once (sparse LU) for
the constraint modes, the shift-invert Lanczos at shift 0 (``K_ii`` is positive definite once
the interface is held) and the residual flexibility; a rigid interface with nothing else held
has the body's rigid motions as constraint modes, in closed form.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import ConfigError
from ..fe.elasticity import (free_dofs, lame_2d, rigid_null_space, shift_invert_modes,
                             count_below, single_threaded_blas, symmetric_lu)
from .body import ReducedBody
from .residual import ResidualFlexibility

#: Relative gap below which two frequencies count as one (degenerate) cluster; a cutoff never
#: separates the members of a cluster (cyclic symmetry needs both modes of a pair).
CLUSTER_GAP = 1e-3

#: Modes asked beyond the inertia count of the band: the first mode above the band shows
#: whether a degenerate cluster straddles the cutoff. ARPACK iterates until every asked mode has
#: converged, and the last ones of the block converge slowest, so each further mode costs
#: solves: one is enough.
COUNT_MARGIN = 1

#: Columns per SuperLU solve of a block of right-hand sides. The triangular sweeps stream the
#: factors once per call, so a block is cheaper per column than single solves; past a few
#: columns the right-hand sides no longer stay in cache (8 was the fastest block on the ring
#: and the sun).
SOLVE_BLOCK = 8


class ClampedFactorisation:
    """Sparse LU of ``K_ii`` (interface and fixed dofs held); solves for full-size vectors.

    Parameters
    ----------
    model : FEModel or any object with ``K``, ``M``, ``ndofs``
    held : array_like of int
        Dofs held at zero (interface boundary and fixed dofs).
    """

    def __init__(self, model, held):
        self.model = model
        self.held = np.asarray(held, dtype=np.int64)
        self._lu = None
        self._inner = None
        self.seconds = 0.0

    @property
    def ndofs(self) -> int:
        return self.model.ndofs

    @property
    def inner(self) -> np.ndarray:
        """Dofs not held (sorted)."""
        if self._inner is None:
            self._inner = free_dofs(self.model.ndofs, self.held)
            if self._inner.size < 2:
                raise ConfigError("the interface holds every dof: nothing left to reduce")
        return self._inner

    @property
    def K(self):
        """``K_ii`` (sparse CSC) [N/m]."""
        return self.model.K[self.inner][:, self.inner].tocsc()

    @property
    def M(self):
        """``M_ii`` (sparse CSC) [kg]."""
        return self.model.M[self.inner][:, self.inner].tocsc()

    @property
    def lu(self):
        """Sparse LU of ``K_ii``, made on first use (a body loaded from the cache only factorises
        when its residual flexibility is applied to a new load)."""
        if self._lu is None:
            t0 = time.perf_counter()
            try:
                # K_ii is symmetric positive definite: symmetric ordering, no pivoting (37 % less
                # fill than the default COLAMD on a level-2 gear, so faster solves)
                self._lu = symmetric_lu(self.K)
            except RuntimeError as exc:
                raise ConfigError(f"the stiffness with the interface held is singular ({exc}): "
                                  "the interface does not stop every rigid-body motion") from exc
            self.seconds = time.perf_counter() - t0
        return self._lu

    def solve_inner(self, b):
        """``K_ii^-1 b`` for vectors on the inner dofs; a block (n_inner, k) in blocks of
        :data:`SOLVE_BLOCK` columns (SuperLU's multi-column solve)."""
        b = np.asarray(b, dtype=float)
        if b.ndim == 1:
            return self.lu.solve(np.ascontiguousarray(b))
        x = np.empty_like(b)
        for j in range(0, b.shape[1], SOLVE_BLOCK):
            x[:, j:j + SOLVE_BLOCK] = self.lu.solve(np.asfortranarray(b[:, j:j + SOLVE_BLOCK]))
        return x

    def solve(self, F):
        """``K_ii^-1 F[inner]`` scattered into full-size vectors (zero on held dofs) [m]."""
        F = np.asarray(F, float)
        U = np.zeros_like(F)
        U[self.inner] = self.solve_inner(F[self.inner])
        return U


def weyl_mode_count(model, cutoff_hz: float) -> float:
    """Weyl estimate of the number of in-plane modes below ``cutoff_hz`` [-].

    ``N ~ A omega^2 / (4 pi) (1/c_L^2 + 1/c_T^2)`` for a 2D elastic body of area A, with the
    plane wave speeds ``c_L^2 = (lambda_2D + 2 mu)/rho``, ``c_T^2 = mu/rho``. Used only to size
    the first eigen-solve.
    """
    mat = getattr(model, "material", None)
    if mat is None:
        return 10.0
    lam, mu = lame_2d(mat, getattr(model, "formulation", "plane_stress"))
    rho = mat.rho
    area = model.mass() / (rho * model.thickness)
    w = 2.0 * math.pi * cutoff_hz
    return area * w * w / (4.0 * math.pi) * (rho / (lam + 2 * mu) + rho / mu)


class Reductor:
    """Common part: resolve the interface, factorise ``K_ii``, build constraint modes.

    Parameters
    ----------
    model : FEModel
    interface : NodalInterface or RigidInterface (anything with ``resolve(model)``)
    """

    method = ""

    def __init__(self, model, interface):
        if not hasattr(interface, "resolve"):
            raise ConfigError(f"interface = {interface!r}: must be a NodalInterface or "
                              "RigidInterface")
        self.model = model
        self.imap = interface.resolve(model)
        held = np.union1d(self.imap.boundary, self.imap.fixed)
        loose = rigid_null_space(model, held).shape[1]
        if loose:
            raise ConfigError(f"interface holds {held.size} dofs but leaves {loose} rigid-body "
                              "motion(s) free with its coordinates held: a body needs a support "
                              "(bore, rim, bolts or fixed dofs) that stops every rigid motion")
        self.factor = ClampedFactorisation(model, held)
        self.factor.inner  # noqa: B018 - raises early if the interface holds every dof
        #: constraint modes are the body's rigid motions (rigid interface, nothing else held)
        self.rigid_constraint_modes = bool(self.imap.rigid and self.imap.fixed.size == 0
                                           and hasattr(model, "rigid_body_modes"))

    def constraint_modes(self) -> np.ndarray:
        """``Psi`` (ndofs, nq): static shapes for unit interface coordinates [m per unit]."""
        im, model = self.imap, self.model
        if self.rigid_constraint_modes:
            R = model.rigid_body_modes()
            # rigid motion about the frame centre: shift the rotation column
            R[:, 2] += im.centre[1] * R[:, 0] - im.centre[0] * R[:, 1]
            return R
        Psi = np.zeros((model.ndofs, im.n_coordinates))
        Psi[im.boundary] = im.T
        K = model.K.tocsr()
        Kib = K[self.factor.inner][:, im.boundary]
        Psi[self.factor.inner] = -self.factor.solve_inner(np.asarray(Kib @ im.T))
        return Psi

    def _body(self, basis, n_modes_freqs, modes, omega2, t0):
        with single_threaded_blas():
            return self._project(basis, n_modes_freqs, modes, omega2, t0)

    def _project(self, basis, n_modes_freqs, modes, omega2, t0):
        model = self.model
        KV = model.K @ basis
        MV = model.M @ basis
        Kr = basis.T @ KV
        Mr = basis.T @ MV
        Kr = 0.5 * (Kr + Kr.T)
        if self.rigid_constraint_modes:
            # K R = 0 exactly for rigid motions; drop the round-off
            nq0 = self.imap.n_coordinates
            Kr[:nq0, :] = 0.0
            Kr[:, :nq0] = 0.0
        Mr = 0.5 * (Mr + Mr.T)
        nq = self.imap.n_coordinates
        nm = basis.shape[1] - nq
        names = tuple(self.imap.names) + tuple(f"eta{k}" for k in range(nm))
        residual = ResidualFlexibility(self.factor, modes, omega2)
        info = {"ndofs": model.ndofs, "n_inner": int(self.factor.inner.size),
                "factor_seconds": self.factor.seconds, "seconds": time.perf_counter() - t0}
        return ReducedBody(K=Kr, M=Mr, basis=basis, n_interface=nq,
                           frequencies=n_modes_freqs, names=names, model=model,
                           interface=self.imap, residual=residual, method=self.method,
                           info=info)


class GuyanReductor(Reductor):
    """Static (Guyan) condensation onto the interface coordinates.

    ``V = Psi``; exact for any static load applied on the interface dofs. The body's residual
    flexibility is the whole ``K_ii^-1`` (no modes kept).
    """

    method = "guyan"

    def reduce(self) -> ReducedBody:
        """Return the reduced body."""
        t0 = time.perf_counter()
        Psi = self.constraint_modes()
        return self._body(Psi, np.zeros(0), np.zeros((self.model.ndofs, 0)), np.zeros(0), t0)


class CraigBamptonReductor(Reductor):
    """Craig-Bampton: constraint modes plus fixed-interface modes up to a cutoff.

        Parameters
        ----------
        model : FEModel
        interface : NodalInterface or RigidInterface
        cutoff : float, optional
            Keep the modes with frequency <= cutoff [Hz] (a degenerate pair at the cutoff kept
            whole, :data:`CLUSTER_GAP`).
        n_modes : int, optional
            Keep exactly this many modes instead (give ``cutoff`` or ``n_modes``, not both).
        augment : bool
            Append the modal truncation augmentation vectors (:meth:`augmentation`): the interior's
            static response to the constraint modes' inertia loads ``M Psi``, M-orthogonalised and
            diagonalised, so the left-out modes answer the interface's accelerations
            quasi-statically. Default False.

        Raises
        ------
        ConfigError
            Cutoff non-positive or below the first fixed-interface mode (the message gives it);
            n_modes not a positive integer smaller than the inner dofs; both or neither given.
    """

    method = "craig_bampton"

    def __init__(self, model, interface, cutoff: float | None = None, n_modes: int | None = None,
                 augment: bool = False):
        self.augment = bool(augment)
        if (cutoff is None) == (n_modes is None):
            raise ConfigError(f"cutoff = {cutoff!r}, n_modes = {n_modes!r}: give exactly one")
        if cutoff is not None:
            if isinstance(cutoff, bool) or not isinstance(cutoff, (int, float)) \
                    or not math.isfinite(cutoff) or cutoff <= 0:
                raise ConfigError(f"cutoff = {cutoff!r}: the mode cutoff must be a frequency "
                                  "> 0 Hz")
        if n_modes is not None:
            if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) \
                    or n_modes < 1:
                raise ConfigError(f"n_modes = {n_modes!r}: must be an integer >= 1")
        super().__init__(model, interface)
        n_inner = self.factor.inner.size
        if n_modes is not None and n_modes >= n_inner:
            raise ConfigError(f"n_modes = {n_modes}: must be below the {n_inner} inner dofs")
        self.cutoff = None if cutoff is None else float(cutoff)
        self.n_modes = None if n_modes is None else int(n_modes)

    def fixed_interface_modes(self):
        """``(omega2 (k,), shapes (ndofs, k))`` of the kept fixed-interface modes."""
        f = self.factor
        what = f"fixed-interface modes ({f.inner.size} inner dofs)"
        n_inner = f.inner.size
        Kii, Mii = f.K, f.M
        if self.n_modes is not None:
            lam, vec = shift_invert_modes(Kii, Mii, self.n_modes, 0.0, solve=f.solve_inner,
                                          what=what)
        else:
            wc2 = (2.0 * math.pi * self.cutoff) ** 2
            upper = wc2 * (1.0 + CLUSTER_GAP) ** 2
            # the number of modes below the cutoff (and its cluster gap) from the inertia of
            # K_ii - upper M_ii: one factorisation sizes the Lanczos block exactly, one more
            # for a mode above the band (COUNT_MARGIN). Without it (SuperLU pivoted) the first block is sized
            # by Weyl's law plus 10, at least 20 (Weyl undercounts a toothed outline, whose free
            # boundary adds modes: then further blocks follow with the modes found so far
            # deflated, no work repeated, but more solves than one block of the right size).
            n_below = count_below(Kii, Mii, upper)
            if n_below is None:
                k = max(20, math.ceil(weyl_mode_count(self.model, self.cutoff)) + 10)
            else:
                k = n_below + COUNT_MARGIN
            self._check_count(k, n_inner)
            lam, vec = shift_invert_modes(Kii, Mii, k, 0.0, solve=f.solve_inner, what=what)
            if lam[0] > wc2:
                f1 = math.sqrt(lam[0]) / (2.0 * math.pi)
                raise ConfigError(f"cutoff = {self.cutoff:.6g} Hz: lies below the first "
                                  f"fixed-interface mode ({f1:.6g} Hz); raise the cutoff")
            while (lam[-1] <= upper or (n_below is not None and
                                        np.count_nonzero(lam < upper) < n_below)) \
                    and lam.size < n_inner - 1:
                k = int(min(n_inner - 1 - lam.size, max(10, lam.size // 2)))
                lam2, vec2 = shift_invert_modes(Kii, Mii, k, 0.0, solve=f.solve_inner,
                                                deflate=vec, what=what)
                lam, vec = np.concatenate([lam, lam2]), np.hstack([vec, vec2])
                order = np.argsort(lam)
                lam, vec = lam[order], vec[:, order]
            keep = int(np.searchsorted(lam, wc2, side="right"))
            while keep < lam.size and lam[keep] <= lam[keep - 1] * (1.0 + CLUSTER_GAP) ** 2:
                keep += 1
            lam, vec = lam[:keep], vec[:, :keep]
        shapes = np.zeros((self.model.ndofs, lam.size))
        shapes[f.inner] = vec
        return lam, shapes

    def _check_count(self, k: int, n_inner: int) -> None:
        """Raise ConfigError if ``k`` modes below the cutoff are nearly all ``n_inner`` of the mesh
        (a cutoff given in the wrong unit: the highest modes of a mesh are its discretisation)."""
        if k >= n_inner - 1:
            raise ConfigError(f"cutoff = {self.cutoff:.6g} Hz: about {k} of the mesh's {n_inner} interior modes lie "
                              "below it, nearly all (the highest modes of a mesh are its discretisation, not the "
                              "body's); lower the cutoff")

    def augmentation(self, Psi, Phi):
        """``(lam (k,), X (ndofs, k))``: the modal truncation augmentation vectors.

        ``X0 = K_ii^-1 (M Psi)_i`` (interface held), projected M-orthogonally off the kept modes
        ``Phi``, then the Ritz vectors of ``(K_ii, M_ii)`` on that span: M-orthonormal,
        K-orthogonal to each other and to ``Phi`` and ``Psi``, so that the reduced stiffness stays
        block diagonal. A direction whose share of ``X0`` falls below 1e-10 (dependent loads) is
        dropped. J. M. Dickens, J. M. Nakagawa and M. J. Wittbrodt, "A critique of mode
        acceleration and modal truncation augmentation methods for modal response analysis",
        *Computers & Structures* 62(6), 985-998, 1997.
        """
        f = self.factor
        Mii, Kii = f.M, f.K
        X = f.solve_inner(np.asarray((self.model.M @ Psi)[f.inner]))
        P = Phi[f.inner]
        for _ in range(2):  # twice: classical Gram-Schmidt loses orthogonality once
            X -= P @ (P.T @ (Mii @ X))
        g = X.T @ (Mii @ X)
        s, U = np.linalg.eigh(0.5 * (g + g.T))
        keep = s > 1e-10 * s.max()
        Y = X @ (U[:, keep] / np.sqrt(s[keep]))
        k = Y.T @ (Kii @ Y)
        lam, Z = np.linalg.eigh(0.5 * (k + k.T))
        shapes = np.zeros((self.model.ndofs, lam.size))
        shapes[f.inner] = Y @ Z
        return lam, shapes

    def reduce(self) -> ReducedBody:
        """Return the reduced body (coordinates: interface, then modes)."""
        t0 = time.perf_counter()
        Psi = self.constraint_modes()
        t1 = time.perf_counter()
        omega2, Phi = self.fixed_interface_modes()
        t2 = time.perf_counter()
        n_aug = 0
        if self.augment:
            lam, X = self.augmentation(Psi, Phi)
            omega2, Phi, n_aug = np.concatenate([omega2, lam]), np.hstack([Phi, X]), lam.size
        basis = np.hstack([Psi, Phi])
        body = self._body(basis, np.sqrt(omega2) / (2.0 * math.pi), Phi, omega2, t0)
        body.info.update({"constraint_seconds": t1 - t0, "eigen_seconds": t2 - t1,
                          "cutoff_hz": self.cutoff, "augmentation_vectors": n_aug})
        return body
