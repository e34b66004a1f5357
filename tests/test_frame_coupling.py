"""The inertia coupling between a flexible gear's floating frame and its modes, against a
construction of its own from the FE mass matrix.

A material point of the gear sits at ``u = x0 + R(theta) (X + Phi eta)`` (X: node positions
about the gear axis, Phi: the fixed-interface modes, R: the turn by the frame angle, acting on
every node). With the consistent mass matrix M of the FE body the kinetic energy is
``T = 1/2 u'^T M u'`` and, at eta = 0, ``u' = B [x0', y0', theta', eta']`` with the columns
``B = [e_x, e_y, R E X, R Phi]`` (e_x, e_y: unit translations, E X = (-Y, X): the rotation
field). So the mass matrix of the frame coordinates and the modes is ``B^T M B``; its
off-diagonal block ``(R Phi)^T M [e_x, e_y, R E X]`` is the frame-mode coupling whose sign
decides whether the frame's acceleration loads the modes or unloads them. Here M is assembled
with scikit-fem on the gear's own basis and the rigid fields are interpolated on it, apart from
the package's reduction code (only the modes Phi are taken from the reduction).

Checks: the solver's assembled mass matrix (modes as coordinates, :mod:`flexgear.dynamics.
floating_frame`) equals B^T M B to round-off at two frame angles; condensed modes (integrated
or quasi-static, :mod:`flexgear.dynamics.flexible.condensed`) under a constant angular acceleration of
the frame settle at the one-mode closed form ``eta_i = -S_r,i theta'' / omega_i^2`` (the static
response of eta_i'' + omega_i^2 eta_i = -S_r,i theta'', Lagrange's equation of that T).
"""
import copy
import math
import tomllib

import numpy as np
import pytest
from skfem import BilinearForm
from skfem.helpers import dot

from flexgear.config import parse_config, preset_path
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.flexible.reductions import reduce_flexible_gears
from flexgear.dynamics.integrator.simulation import evaluate, simulate

SPUR = tomllib.loads(preset_path("spur_pair").read_text())


def _config(flexible, **changes):
    doc = copy.deepcopy(SPUR)
    doc["flexible"] = dict({"level": 1, "formulation": "plane_stress"}, **flexible)
    for key, value in changes.items():
        section, name = key.split(".")
        doc[section][name] = value
    return parse_config(doc)


def _free(cfg, reductions):
    """The model without meshes and applied torques: a free body."""
    m = build_model(cfg, reductions=reductions)
    m.meshes = []
    for b in m.bodies:
        b.torque = None
    return m


def full_order_shapes(fe):
    """Consistent mass [kg] assembled here on the FE body's basis, and the unit translations
    and the rotation field about the gear axis (origin) interpolated on it (exact: linear)."""
    rho, t = fe.material.rho, fe.thickness
    M = BilinearForm(lambda u, v, w: rho * t * dot(u, v)).assemble(fe.basis)
    zero = lambda x: 0.0 * x[0]  # noqa: E731
    ex = fe.basis.project(lambda x: np.array([1.0 + zero(x), zero(x)]))
    ey = fe.basis.project(lambda x: np.array([zero(x), 1.0 + zero(x)]))
    et = fe.basis.project(lambda x: np.array([-x[1], x[0]]))
    return M, ex, ey, et


def _turn(fe, u, angle):
    """Every node's displacement of ``u`` turned by ``angle``."""
    c, s = math.cos(angle), math.sin(angle)
    ix, iy = fe.node_dofs[:, 0], fe.node_dofs[:, 1]
    out = np.empty_like(u)
    out[ix] = c * u[ix] - s * u[iy]
    out[iy] = s * u[ix] + c * u[iy]
    return out


@pytest.fixture(scope="module")
def wheel_on_bearing():
    """The spur wheel, flexible (level 1), on an elastic bearing (x, y, theta free), its three
    modes below 60 kHz (43.2, 54.2, 54.2 kHz: a torsional one and a translating pair) as
    coordinates; no mesh, no torque."""
    cfg = _config({"gears": ["wheel"], "dynamic_cutoff": 60e3}, **{"supports.wheel": {"stiffness": 1e8}})
    reds = reduce_flexible_gears(cfg)
    return _free(cfg, reds), reds["wheel"]


@pytest.mark.parametrize("turn", [0.4, 2.5])
def test_modal_coordinates_mass_matrix_is_the_full_order_kinetic_energy(wheel_on_bearing, turn):
    """Mq of the wheel's x, y, theta and modes (``evaluate``) against B^T M B at the frame
    angle theta_0 + ``turn``: the coupling blocks (both triangles) and the modal block to 1e-9 of
    the largest coupling; the rigid block to 1e-3 (the model takes the rigid mass and inertia
    from the exact outline, the FE mesh from its polygon). A coupling of the wrong sign is off by
    twice its size, 2e9 x the bar."""
    m, red = wheel_on_bearing
    assert m.coordinate_names() == ["wheel.x", "wheel.y", "wheel.theta", "wheel.eta1", "wheel.eta2", "wheel.eta3"]
    fe, nq = red.body.model, red.body.n_interface
    M, ex, ey, et = full_order_shapes(fe)
    mass = ex @ M @ ex
    assert max(abs(ex @ M @ et), abs(ey @ M @ et)) < 1e-9 * mass * 0.03  # frame origin on the axis
    q, v = m.initial_state()
    q[2] += turn
    Phi = red.body.basis[:, nq:nq + 3]
    B = np.column_stack([ex, ey, _turn(fe, et, q[2])] + [_turn(fe, Phi[:, i], q[2]) for i in range(3)])
    ref = B.T @ (M @ B)
    Mq = evaluate(m, q, v)["Mq"]
    coupling = np.abs(ref[3:, :3]).max()
    assert coupling > 1e-3 * math.sqrt(ref[0, 0])  # the modes couple to the frame (sqrt(kg), sqrt(kg) m)
    assert np.abs(Mq[3:, :3] - ref[3:, :3]).max() < 1e-9 * coupling
    assert np.abs(Mq[:3, 3:] - ref[:3, 3:]).max() < 1e-9 * coupling
    assert np.abs(Mq[3:, 3:] - ref[3:, 3:]).max() < 1e-9
    assert np.allclose(np.diag(Mq)[:3], np.diag(ref)[:3], rtol=1e-3, atol=0)


@pytest.mark.parametrize("condensation", ["integrated", "static"])
def test_condensed_modes_settle_at_the_frames_inertia_load(condensation):
    """The spur pinion, flexible (level 1, every mode condensed, 10 % modal damping), its
    prescribed speed ramped from 0 to 10 Hz over 10 ms (theta'' = 6283 rad/s^2); the wheel free
    and unloaded, the teeth thinned by 0.6 mm so that they do not touch within the 2 ms run (the
    condensed modes are integrated in the contact solve, which needs a mesh). Once the start
    transient has decayed (the slowest mode, 31 kHz, rings down as exp(-2e4 t)) each condensed
    mode carries the frame's inertia load statically, eta_i = -S_r,i theta'' / omega_i^2 with
    S_r,i = Phi_i^T M (E X) from the FE mass assembled here: within 1e-6 of the largest (the
    model leaves the centrifugal terms out; there is no contact force). A coupling of the wrong
    sign is off by twice the response, 2e6 x the bar."""
    cfg = _config({"gears": ["pinion"], "dynamic_cutoff": 0.0, "modal_damping": 0.1},
                  **{"drive.speed_hz": [[0.0, 0.0], [0.01, 10.0]], "gear_defaults.thinning": 6e-4})
    reds = reduce_flexible_gears(cfg)
    m = build_model(cfg, reductions=reds)
    for b in m.bodies:
        b.torque = None
    red = reds["pinion"]
    fe, nq = red.body.model, red.body.n_interface
    M, _, _, et = full_order_shapes(fe)
    S_r = red.body.basis[:, nq:].T @ (M @ et)
    omega = 2 * math.pi * red.body.frequencies
    expected = -S_r * (2 * math.pi * 10.0 / 0.01) / omega ** 2
    h, n = 1e-5, 200
    r = simulate(m, n * h, h, 1, condensation=condensation)
    assert np.abs(r.records.mesh_force).max() == 0.0
    eta = r.condensed[-1]
    assert eta.shape == expected.shape
    assert np.abs(expected).max() > 1e-9  # a response [sqrt(kg) m] far above round-off
    assert np.abs(eta - expected).max() < 1e-6 * np.abs(expected).max()
