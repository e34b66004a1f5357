"""Linear elastic finite element matrices (scikit-fem) and the analyses built on them.

Pipeline position: ``meshing -> fe -> reduction``. :func:`assemble` builds the stiffness
``K`` [N/m] and consistent mass ``M`` [kg] of a planar body (plane stress, default, or plane
strain) of out-of-plane thickness ``thickness`` [m] (the face width). :func:`clamped_modes`
and :func:`static_solve` only use ``model.K``, ``model.M`` and ``model.ndofs``, so they work
for any model with those attributes (e.g. a 3D model).

Formulations (Lamé parameters from E [Pa], nu [-])::

    mu = E / (2 (1 + nu)),  lambda = E nu / ((1 + nu)(1 - 2 nu))
    plane strain:  lambda_2D = lambda
    plane stress:  lambda_2D = 2 lambda mu / (lambda + 2 mu)  (= E nu / (1 - nu^2))

``K = t * int(sigma(u) : eps(v))``, ``M = rho * t * int(u . v)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

from ..errors import ConfigError, EigenSolveError
from ..gears.material import Material

FORMULATIONS = ("plane_stress", "plane_strain")


@dataclass
class FEModel:
    """Assembled linear elastic model.

    Attributes
    ----------
    K : scipy.sparse.csr_matrix, (ndofs, ndofs)
        Stiffness [N/m], symmetric positive semi-definite.
    M : scipy.sparse.csr_matrix, (ndofs, ndofs)
        Consistent mass [kg], symmetric positive definite.
    basis : skfem.Basis
        Vector basis (ElementVector of P1 or P2) the matrices were assembled on.
    mesh : skfem.Mesh
        The scikit-fem mesh (with named ``boundaries``).
    material : Material
    thickness : float
        Out-of-plane thickness (face width) [m].
    formulation : str
        ``"plane_stress"`` or ``"plane_strain"``.
    node_dofs : ndarray, (n_nodes, dim) int
        Global dof index of each node and displacement component. Node numbering is that of
        the :class:`~flexgear.fe.meshing.GearMesh` if one was given, else vertices then edge
        mid-nodes of the skfem mesh.
    node_coords : ndarray, (n_nodes, dim)
        Node coordinates [m].
    node_sets : dict[str, ndarray]
        Named node sets (from the GearMesh boundary groups).
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    basis: object
    mesh: object
    material: Material
    thickness: float
    formulation: str
    node_dofs: np.ndarray
    node_coords: np.ndarray
    node_sets: dict = field(default_factory=dict)

    @property
    def ndofs(self) -> int:
        """Number of degrees of freedom."""
        return self.K.shape[0]

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.node_dofs.shape[0]

    def nodal_dofs(self, node_idx) -> np.ndarray:
        """Dofs of the given nodes, shape ``(len(node_idx), dim)``; column c = component c."""
        return self.node_dofs[np.asarray(node_idx, dtype=np.int64)]

    def group_dofs(self, name: str) -> np.ndarray:
        """Sorted dofs (all components) of the nodes of boundary group ``name``."""
        if name not in self.node_sets:
            raise KeyError(f"no node set {name!r}; available: {sorted(self.node_sets)}")
        return np.sort(self.nodal_dofs(self.node_sets[name]).ravel())

    def nodal_field(self, u: np.ndarray) -> np.ndarray:
        """Displacement vector(s) ``u`` (ndofs[, k]) as nodal values (n_nodes, dim[, k]) [m]."""
        return np.asarray(u)[self.node_dofs]

    def rigid_body_modes(self) -> np.ndarray:
        """Columns: translation x, translation y, rotation about the origin (2D) [m]."""
        x, y = self.node_coords[:, 0], self.node_coords[:, 1]
        R = np.zeros((self.ndofs, 3))
        R[self.node_dofs[:, 0], 0] = 1.0
        R[self.node_dofs[:, 1], 1] = 1.0
        R[self.node_dofs[:, 0], 2] = -y
        R[self.node_dofs[:, 1], 2] = x
        return R

    def mass(self) -> float:
        """Total mass [kg] (from the consistent mass matrix, x direction)."""
        e = np.zeros(self.ndofs)
        e[self.node_dofs[:, 0]] = 1.0
        return float(e @ (self.M @ e))


def lame_2d(material: Material, formulation: str = "plane_stress") -> tuple[float, float]:
    """In-plane Lamé parameters ``(lambda_2D, mu)`` [Pa] for the formulation."""
    if formulation not in FORMULATIONS:
        raise ConfigError(f"formulation = {formulation!r}: must be one of {FORMULATIONS}")
    E, nu = material.E, material.nu
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if formulation == "plane_stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def _node_dof_map(gear_mesh, skmesh, basis) -> np.ndarray:
    """(n_nodes, 2) dofs of each node: GearMesh numbering if given, else skfem numbering."""
    nd, fd = basis.nodal_dofs, basis.facet_dofs
    nv = nd.shape[1]
    if gear_mesh is None:
        parts = [nd.T]
        if fd.size:
            parts.append(fd.T)
        return np.ascontiguousarray(np.vstack(parts), dtype=np.int64)
    from .meshing import FacetLookup

    out = np.full((gear_mesh.n_nodes, 2), -1, dtype=np.int64)
    out[:nv] = nd.T[:nv]
    if gear_mesh.order == 2:
        tri = gear_mesh.triangles
        look = FacetLookup(skmesh.facets, nv)
        for j, (a, b) in ((3, (0, 1)), (4, (1, 2)), (5, (2, 0))):
            out[tri[:, j]] = fd.T[look(tri[:, a], tri[:, b])]
    if np.any(out < 0):
        raise RuntimeError("node-to-dof map incomplete")
    return out


def assemble(mesh, material: Material, thickness: float,
             formulation: str = "plane_stress") -> FEModel:
    """Assemble stiffness and consistent mass of a planar elastic body.

    Parameters
    ----------
    mesh : flexgear.meshing.GearMesh or skfem.MeshTri1 / skfem.MeshTri2
        The body. Element: vector P1 for 3-node, vector P2 for 6-node triangles.
    material : Material
        E [Pa], nu [-], rho [kg/m^3].
    thickness : float or dict[str, float]
        Out-of-plane thickness (the face width) [m]; multiplies K and M. A dict gives one per
        region of ``mesh.regions`` (every region; a housing's wall and cover); the model's
        ``thickness`` is then the area-weighted mean.
    formulation : {"plane_stress", "plane_strain"}
        Plane stress (thin disc, default) or plane strain.

    Returns
    -------
    FEModel
    """
    from skfem import Basis, BilinearForm, ElementTriP1, ElementTriP2, ElementVector, MeshTri2
    from skfem.helpers import ddot, dot, sym_grad, trace, eye

    per_region = isinstance(thickness, dict)
    if per_region:
        regions = getattr(mesh, "regions", {}) or {}
        if set(thickness) != set(regions) or not all(np.isfinite(t) and t > 0 for t in thickness.values()):
            raise ConfigError(f"thickness = {thickness!r}: one thickness > 0 m per mesh region "
                              f"({', '.join(sorted(regions)) or 'the mesh has none'})")
    elif not (np.isfinite(thickness) and thickness > 0):
        raise ConfigError(f"thickness = {thickness!r}: must be > 0 m")
    if not isinstance(material, Material):
        raise ConfigError(f"material = {material!r}: must be a flexgear.material.Material")
    lam, mu = lame_2d(material, formulation)

    gear_mesh = None
    node_sets = {}
    if hasattr(mesh, "to_skfem"):
        gear_mesh = mesh
        node_sets = dict(mesh.node_sets)
        skmesh = mesh.to_skfem()
    else:
        skmesh = mesh
    if skmesh.dim() != 2:
        raise ConfigError(f"mesh dimension = {skmesh.dim()}: assemble() is for 2D meshes")
    quadratic = isinstance(skmesh, MeshTri2)
    elem = ElementVector(ElementTriP2() if quadratic else ElementTriP1())
    intorder = 4 if quadratic else 2
    basis = Basis(skmesh, elem, intorder=intorder)

    t, rho = (1.0 if per_region else float(thickness)), float(material.rho)

    @BilinearForm
    def stiffness(u, v, w):
        eu = sym_grad(u)
        sig = 2.0 * mu * eu + lam * eye(trace(eu), 2)
        return t * ddot(sig, sym_grad(v))

    @BilinearForm
    def mass(u, v, w):
        return rho * t * dot(u, v)

    if per_region:  # K = sum_r t_r K_r over the regions' elements
        K = M = None
        area = weighted = 0.0
        for name, tr in thickness.items():
            sub = Basis(skmesh, elem, intorder=intorder, elements=mesh.regions[name])
            Kr, Mr = tr * stiffness.assemble(sub), tr * mass.assemble(sub)
            K, M = (Kr, Mr) if K is None else (K + Kr, M + Mr)
            a = float(np.sum(sub.dx))
            area, weighted = area + a, weighted + a * tr
        K, M = K.tocsr(), M.tocsr()
        t = weighted / area
    else:
        K = stiffness.assemble(basis).tocsr()
        M = mass.assemble(basis).tocsr()
    # remove round-off asymmetry
    K = ((K + K.T) * 0.5).tocsr()
    M = ((M + M.T) * 0.5).tocsr()
    node_dofs = _node_dof_map(gear_mesh, skmesh, basis)
    if gear_mesh is not None:
        coords = gear_mesh.points.copy()
    else:
        coords = basis.doflocs[:, node_dofs[:, 0]].T.copy()
    return FEModel(K, M, basis, skmesh, material, t, formulation, node_dofs, coords, node_sets)


def single_threaded_blas():
    """Context in which BLAS runs on one thread (restored afterwards; ``threadpoolctl``), for the
    FE and reduction linear algebra. A threaded BLAS splits its sums by the thread count, so the
    same gear reduced on a machine with other cores, or in a worker given fewer threads, would
    differ in its last bits, and so would every run on it; and ARPACK's small dense updates gain
    nothing from BLAS threads, whose spinning slows the eigen-solve on a busy machine."""
    return threadpool_limits(limits=1, user_api="blas")


def free_dofs(ndofs: int, fixed_dofs) -> np.ndarray:
    fixed = np.unique(np.asarray(fixed_dofs if fixed_dofs is not None else [], dtype=np.int64))
    if fixed.size and (fixed[0] < 0 or fixed[-1] >= ndofs):
        raise ConfigError(f"fixed_dofs: indices must lie in 0..{ndofs - 1}")
    mask = np.ones(ndofs, dtype=bool)
    mask[fixed] = False
    return np.flatnonzero(mask)


#: ARPACK's relative accuracy of the Ritz values in :func:`shift_invert_modes` (the residuals
#: come out near 1e-9 or better; every pair is still checked against EIGEN_RESIDUAL_TOL). With
#: a Lanczos basis of 1.5 k + 20 vectors for k >= 40 modes, it saves a quarter of the time of
#: ARPACK's defaults (tol = machine precision, 2 k + 1 vectors) at 100 modes.
LANCZOS_TOL = 1e-10

#: Largest accepted relative residual of an eigenpair (see :func:`eigen_residuals`).
EIGEN_RESIDUAL_TOL = 1e-6


def eigen_residuals(K, M, lam, vec) -> np.ndarray:
    """Relative residuals of eigenpairs of ``K x = lam M x``.

    ``r_j = ||K x_j - lam_j M x_j|| / max(||K x_j||, |lam_j| ||M x_j||, lam_s ||M x_j||)`` with
    ``lam_s = max_j |lam_j|`` the scale of the band: for elastic modes this is the usual
    ``||K x - w^2 M x|| / ||K x||``; a rigid-body mode (lam = 0, ``K x`` pure round-off) is
    measured against the band instead of against its own round-off.

    Parameters
    ----------
    K, M : sparse matrices (n, n)
    lam : ndarray (k,)
        Eigenvalues omega^2 [rad^2/s^2].
    vec : ndarray (n, k)
        Eigenvectors.
    """
    lam = np.atleast_1d(np.asarray(lam, float))
    vec = np.asarray(vec, float).reshape(K.shape[0], -1)
    Kx, Mx = K @ vec, M @ vec
    nK = np.linalg.norm(Kx, axis=0)
    nM = np.linalg.norm(Mx, axis=0)
    scale = float(np.max(np.abs(lam))) if lam.size else 0.0
    den = np.maximum.reduce([nK, np.abs(lam) * nM, scale * nM])
    num = np.linalg.norm(Kx - Mx * lam, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / den, np.where(num > 0, np.inf, 0.0))


def check_eigenpairs(K, M, lam, vec, what: str = "eigen-solve", tol: float = EIGEN_RESIDUAL_TOL):
    """Raise :class:`~flexgear.errors.EigenSolveError` if a pair's relative residual exceeds ``tol``.

    Returns the residuals (see :func:`eigen_residuals`).
    """
    r = eigen_residuals(K, M, lam, vec)
    bad = np.flatnonzero(~(r <= tol))
    if bad.size:
        f = np.sqrt(np.clip(np.asarray(lam, float)[bad], 0.0, None)) / (2.0 * np.pi)
        raise EigenSolveError(
            f"{what}: relative residual ||K x - w^2 M x|| / ||K x|| = {r[bad].max():.3g} exceeds "
            f"the bound {tol:.1g} for {bad.size} of {r.size} modes (first at {f[0]:.6g} Hz); "
            "the shift is far from the wanted band or a null space was not removed")
    return r


def rigid_null_space(model, fixed_dofs) -> np.ndarray:
    """Rigid-body motions of ``model`` that ``fixed_dofs`` leave free, M-orthonormal columns.

    ``R N`` with ``R = model.rigid_body_modes()`` and ``N`` a basis of the null space of
    ``R[fixed_dofs]`` (all of R when nothing is fixed, none when a bore or rim is clamped).
    Models without ``rigid_body_modes`` (e.g. the 3D sector) give an empty basis.

    Returns
    -------
    ndarray (ndofs, k), k in 0..3, ``X^T M X = I``, zero on ``fixed_dofs``.
    """
    import scipy.linalg as sla

    n = model.ndofs
    if not hasattr(model, "rigid_body_modes"):
        return np.zeros((n, 0))
    R = model.rigid_body_modes()
    fixed = np.unique(np.asarray(fixed_dofs if fixed_dofs is not None else [], dtype=np.int64))
    if fixed.size:
        Rf = R[fixed]
        N = sla.null_space(Rf, rcond=1e-10 * max(1.0, float(np.abs(Rf).max())))
        R = R @ N
    if R.shape[1] == 0:
        return R
    G = R.T @ (model.M @ R)
    L = np.linalg.cholesky(0.5 * (G + G.T))
    return np.linalg.solve(L, R.T).T


def shift_invert_modes(K, M, n_modes: int, sigma: float, solve=None, deflate=None,
                       what: str = "eigen-solve", v0_seed: int = 0):
    """Eigenpairs of ``K x = lam M x`` nearest ``sigma`` by shift-invert Lanczos (``eigsh``).

    Parameters
    ----------
    K, M : sparse matrices (n, n)
        Stiffness [N/m] and mass [kg] (already restricted to the free dofs).
    n_modes : int
        Number of pairs.
    sigma : float
        Shift [rad^2/s^2]; ``K - sigma M`` must be non-singular.
    solve : callable, optional
        ``solve(b) -> (K - sigma M)^-1 b``; a sparse LU is made if omitted (pass one to share
        a factorisation with static solves).
    deflate : ndarray (n, k), optional
        M-orthonormal basis of a known invariant subspace (rigid-body modes) to keep out of the
        Krylov space. Without it a free body's rigid modes, at ``1/(0 - sigma)`` much larger than
        the elastic ``1/(lam - sigma)``, set ARPACK's convergence scale and the elastic pairs come
        out with residuals of order 1.
    what : str
        Name used in the error message.
    v0_seed : int
        Seed of the (deterministic) start vector.

    Returns
    -------
    lam : ndarray (n_modes,), ascending
    vec : ndarray (n, n_modes), mass-normalised

    Raises
    ------
    EigenSolveError
        A residual above :data:`EIGEN_RESIDUAL_TOL`.
    """
    n = K.shape[0]
    if solve is None:
        lu = spla.splu((K - sigma * M).tocsc(), permc_spec="COLAMD")
        solve = lu.solve
    if deflate is not None and deflate.shape[1]:
        X = np.asarray(deflate, float)
        MX = M @ X

        def opinv(b):
            y = solve(b)
            return y - X @ (MX.T @ y)
    else:
        X = None
        opinv = solve
    v0 = np.random.default_rng(v0_seed).standard_normal(n)
    if X is not None:
        v0 -= X @ (MX.T @ v0)
    op = spla.LinearOperator((n, n), matvec=opinv, dtype=float)
    with single_threaded_blas():
        lam, vec = spla.eigsh(K, k=n_modes, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0,
                              ncv=min(n - 1, max(2 * n_modes + 1, 20) if n_modes < 40
                                      else int(1.5 * n_modes) + 20),
                              tol=LANCZOS_TOL)
    order = np.argsort(lam)
    lam, vec = lam[order], vec[:, order]
    vec = vec / np.sqrt(np.einsum("ij,ij->j", vec, M @ vec))
    check_eigenpairs(K, M, lam, vec, what)
    return lam, vec


def symmetric_lu(A):
    """Sparse LU of a symmetric matrix with a symmetric ordering and no pivoting (SuperLU).

    ``P A P^T = L U`` with ``U = D L^T``: 37 % less fill than the default COLAMD ordering on a
    level-2 gear, and the pivots ``diag(U)`` give the inertia of ``A`` (:func:`negative_pivots`).

    Raises
    ------
    RuntimeError
        ``A`` is singular (SuperLU's message).
    """
    return spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def negative_pivots(lu) -> int | None:
    """Number of negative eigenvalues of a symmetric ``A`` from its :func:`symmetric_lu`.

    Sylvester's law of inertia on ``P A P^T = L D L^T`` (``D = diag(U)``); for ``A = K - s M``
    with M positive definite this counts the eigenvalues of ``K x = lam M x`` below ``s``.
    ``None`` when SuperLU exchanged rows (a zero pivot): then ``U`` is no ``D L^T``.
    """
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return int(np.count_nonzero(lu.U.diagonal() < 0.0))


def count_below(K, M, upper: float) -> int | None:
    """Number of eigenvalues of ``K x = lam M x`` below ``upper`` (M positive definite) [-].

    The inertia of ``K - upper M`` (:func:`negative_pivots` of its :func:`symmetric_lu`): one
    factorisation, no eigen-solve. ``None`` when SuperLU had to exchange rows or ``upper`` is an
    eigenvalue (singular).
    """
    try:
        lu = symmetric_lu(sp.csc_matrix(K) - upper * sp.csc_matrix(M))
    except RuntimeError:
        return None
    return negative_pivots(lu)


def clamped_modes(model, fixed_dofs, n_modes: int = 10, sigma: float | None = None):
    """Lowest natural frequencies and mode shapes with ``fixed_dofs`` held at zero.

    Solves ``K phi = omega^2 M phi`` on the free dofs by shift-invert Lanczos (``eigsh``)
    around ``sigma``. Rigid-body motions that ``fixed_dofs`` leave free (all three for a free
    body, see :func:`rigid_null_space`) are taken in closed form as the first modes (0 Hz) and
    deflated from the Lanczos iteration, so the elastic modes converge to the same accuracy
    as for a clamped body. Every pair's residual is checked (:func:`check_eigenpairs`).

    Parameters
    ----------
    model : FEModel or any object with ``K``, ``M`` (sparse) and ``ndofs``
    fixed_dofs : array_like of int
        Dofs held at zero (may be empty: free-free, rigid modes come first at 0 Hz).
    n_modes : int
        Number of modes (rigid ones included).
    sigma : float, optional
        Shift [rad^2/s^2]; default ``-(2 pi * 1 Hz)^2`` (slightly negative, so that free
        bodies with a singular ``K`` can be factorised).

    Returns
    -------
    freqs : ndarray (n_modes,)
        Natural frequencies [Hz], ascending (negative round-off eigenvalues reported as 0).
    shapes : ndarray (ndofs, n_modes)
        Mass-normalised mode shapes (``phi^T M phi = 1``) on all dofs, zero on fixed dofs.

    Raises
    ------
    ConfigError
        ``n_modes`` out of range.
    EigenSolveError
        A residual above :data:`EIGEN_RESIDUAL_TOL`.
    """
    n = model.ndofs
    free = free_dofs(n, fixed_dofs)
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) \
            or not (1 <= n_modes < len(free)):
        raise ConfigError(f"n_modes = {n_modes!r}: must be an integer in 1..{len(free) - 1}")
    if sigma is None:
        sigma = -(2.0 * np.pi) ** 2
    K = model.K[free][:, free].tocsc()
    M = model.M[free][:, free].tocsc()
    rigid = rigid_null_space(model, np.setdiff1d(np.arange(n), free))[free]
    n_rigid = min(rigid.shape[1], n_modes)
    lam = np.zeros(n_modes)
    vec = np.zeros((len(free), n_modes))
    vec[:, :n_rigid] = rigid[:, :n_rigid]
    if n_modes > n_rigid:
        lam_e, vec_e = shift_invert_modes(K, M, n_modes - n_rigid, sigma, deflate=rigid,
                                          what=f"clamped_modes ({len(free)} free dofs)")
        lam[n_rigid:], vec[:, n_rigid:] = lam_e, vec_e
    if n_rigid:
        check_eigenpairs(K, M, lam, vec, f"clamped_modes ({len(free)} free dofs)")
    shapes = np.zeros((n, n_modes))
    shapes[free] = vec
    freqs = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    return freqs, shapes


def static_solve(model, fixed_dofs, f, u_fixed=None) -> np.ndarray:
    """Solve ``K u = f`` with ``u[fixed_dofs] = u_fixed`` (default 0).

    Parameters
    ----------
    model : FEModel or any object with ``K`` and ``ndofs``
    fixed_dofs : array_like of int
        Prescribed dofs (must remove rigid-body motion).
    f : ndarray (ndofs,) or (ndofs, k)
        Nodal force vector(s) [N].
    u_fixed : float or ndarray, optional
        Prescribed values on ``fixed_dofs`` [m].

    Returns
    -------
    ndarray
        Displacements [m], same shape as ``f``.
    """
    n = model.ndofs
    f = np.asarray(f, dtype=float)
    if f.shape[0] != n:
        raise ConfigError(f"f.shape = {f.shape}: first dimension must equal ndofs = {n}")
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    free = free_dofs(n, fixed)
    u = np.zeros_like(f)
    if u_fixed is not None:
        uf = np.broadcast_to(np.asarray(u_fixed, float), (len(fixed),) + f.shape[1:])
        u[fixed] = uf
    K = model.K.tocsr()
    rhs = f[free] - (K[free][:, fixed] @ u[fixed] if fixed.size else 0.0)
    lu = spla.splu(K[free][:, free].tocsc(), permc_spec="COLAMD")
    u[free] = lu.solve(np.asarray(rhs))
    return u



def strain_energy(model, u) -> float:
    """Strain energy ``u^T K u / 2`` [J]."""
    u = np.asarray(u, float)
    return 0.5 * float(u @ (model.K @ u))
