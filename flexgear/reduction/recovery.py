"""Output rows of a reduced body: the motion of a point, from the reduced coordinates.

A sensor's displacement along a unit direction ``d`` at a point ``x`` is ``u_s = r . q`` with

    r = sum_k N_k(xi) (d_x V[dof_x(k)] + d_y V[dof_y(k)])

over the nodes k of the element that holds ``x`` (``xi`` its reference coordinates there, N_k the
element's Lagrange shape functions, V the reduction basis). The row is exact for the reduced
model: its velocity and acceleration are ``r . q_dot`` and ``r . q_ddot``. A point on a curved
edge of a quadratic element is found by Newton's method on the element's isoparametric map.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError

#: largest excursion outside an element's reference triangle still taken as on it (boundary
#: points of a curved outline lie off its quadratic interpolation by far less)
REFERENCE_TOL = 1e-3


def shape_functions(order: int, xi: float, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """``(N (k,), dN (k, 2))`` of the 3-node (order 1) or 6-node (order 2) triangle at
    reference coordinates (xi, eta); nodes: corners (0,0), (1,0), (0,1), then the mid-nodes of
    edges 0-1, 1-2, 2-0 (:class:`~flexgear.fe.meshing.GearMesh` order)."""
    L = np.array([1.0 - xi - eta, xi, eta])
    dL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    if order == 1:
        return L, dL
    N = np.empty(6)
    dN = np.empty((6, 2))
    for i in range(3):
        N[i] = L[i] * (2.0 * L[i] - 1.0)
        dN[i] = (4.0 * L[i] - 1.0) * dL[i]
    for k, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        N[3 + k] = 4.0 * L[i] * L[j]
        dN[3 + k] = 4.0 * (L[i] * dL[j] + L[j] * dL[i])
    return N, dN


def _reference(xe: np.ndarray, order: int, x: np.ndarray) -> np.ndarray:
    """Reference coordinates of ``x`` in the element with nodes ``xe`` (k, 2): Newton's method."""
    a, b, c = xe[0], xe[1], xe[2]
    J = np.column_stack([b - a, c - a])
    xi = np.linalg.solve(J, x - a)
    if order == 1:
        return xi
    for _ in range(20):
        N, dN = shape_functions(2, xi[0], xi[1])
        r = N @ xe - x
        J = xe.T @ dN
        step = np.linalg.solve(J, r)
        xi = xi - step
        if np.max(np.abs(step)) < 1e-14:
            break
    return xi


class PointLocator:
    """Finds the element of a plane mesh that holds a point.

    Parameters
    ----------
    points : ndarray (n_nodes, 2)
        Node coordinates [m].
    triangles : ndarray (n_el, 3) or (n_el, 6)
        Element nodes (:class:`~flexgear.fe.meshing.GearMesh` order).
    """

    def __init__(self, points, triangles):
        from scipy.spatial import cKDTree

        self.points = np.asarray(points, float)
        self.triangles = np.asarray(triangles, np.int64)
        self.order = 1 if self.triangles.shape[1] == 3 else 2
        self._tree = cKDTree(self.points[self.triangles[:, :3]].mean(axis=1))

    def locate(self, x) -> tuple[int, float, float] | None:
        """``(element, xi, eta)`` of point ``x`` [m], or None when it lies outside the mesh
        (farther than :data:`REFERENCE_TOL` of an element, in reference coordinates)."""
        x = np.asarray(x, float)
        k = min(16, len(self.triangles))
        _, cand = self._tree.query(x, k=k)
        best = None
        for e in np.atleast_1d(cand):
            xi = _reference(self.points[self.triangles[e]], self.order, x)
            worst = min(xi[0], xi[1], 1.0 - xi[0] - xi[1])
            if best is None or worst > best[0]:
                best = (worst, int(e), xi)
            if worst >= 0:
                break
        if best is None or best[0] < -REFERENCE_TOL:
            return None
        xi = np.clip(best[2], 0.0, 1.0)
        s = xi.sum()
        if s > 1.0:
            xi = xi / s
        return best[1], float(xi[0]), float(xi[1])


def recovery_row(locator: PointLocator, node_dofs, basis, point, direction, what: str = "point") -> np.ndarray:
    """The row ``r`` (n,) with ``u . d = r . q`` at ``point`` (module docstring).

    Parameters
    ----------
    locator : PointLocator
        Of the mesh the basis was computed on (its node numbering).
    node_dofs : ndarray (n_nodes, 2)
        Dofs of each node (:attr:`flexgear.fe.elasticity.FEModel.node_dofs`).
    basis : ndarray (ndofs, n)
        Reduction basis.
    point : (float, float)
        [m].
    direction : (float, float)
        Unit vector of the measured component.
    what : str
        Names the point in the error message.

    Raises
    ------
    ConfigError
        The point lies off the mesh.
    """
    hit = locator.locate(point)
    if hit is None:
        raise ConfigError(f"{what} at ({point[0]:.6g}, {point[1]:.6g}) m lies off its body's mesh")
    e, xi, eta = hit
    N, _ = shape_functions(locator.order, xi, eta)
    nodes = locator.triangles[e]
    d = np.asarray(direction, float)
    dofs = np.asarray(node_dofs)[nodes]
    return N @ (d[0] * basis[dofs[:, 0]] + d[1] * basis[dofs[:, 1]])


def rigid_row(point, direction, centre=(0.0, 0.0)) -> np.ndarray:
    """The row (3,) of a rigid body's frame coordinates ``(u_x, u_y, theta)`` about ``centre``:
    the displacement along ``direction`` of the body point ``point`` [m per unit coordinate]
    (a sensor on a rigid ring)."""
    d = np.asarray(direction, float)
    r = np.asarray(point, float) - np.asarray(centre, float)
    return np.array([d[0], d[1], -r[1] * d[0] + r[0] * d[1]])
