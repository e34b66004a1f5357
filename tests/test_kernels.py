"""The compiled kernels: named tables, one signature for rigid and flexible models, numba's
disk cache across processes, and the HHT-alpha integrator on a linear oscillator.

The oscillator is one body on a torsional spring (inertia I, stiffness k, no damping) started
from its rest angle with angular velocity w0: theta(t) = (w0 / w) sin(w t), w = sqrt(k / I).
HHT-alpha (beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha) is second-order accurate, so halving
the step divides the error by 4; per step it multiplies the free vibration by the spectral
radius of its amplification matrix (closed form below), which tends to (1 + alpha)/(1 - alpha)
for w h -> infinity (Hilber, Hughes & Taylor 1977; Hughes, The Finite Element Method, 1987,
Sec. 9.3).
"""
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from flexgear.dynamics.model.bodies import ANGLE_SPRING, FIXED, Body, Model
from flexgear.gears.contact_tables import pack_gears
from flexgear.dynamics.integrator.simulation import compiled_cache_present, simulate
from flexgear.dynamics.model.tables import FlexTable, KernelModel, empty_flex

ROOT = Path(__file__).resolve().parents[1]

OSCILLATOR = """
from flexgear.dynamics.model.bodies import ANGLE_SPRING, FIXED, Body, Model
from flexgear.gears.contact_tables import pack_gears

def oscillator(inertia, stiffness, omega0):
    body = Body("rotor", mass=1.0, inertia=inertia, joint=FIXED, rotation=ANGLE_SPRING, theta0=0.0,
                omega0=omega0, torsional_stiffness=stiffness)
    return Model(bodies=[body], meshes=[], tables=pack_gears([]), length_scale=1.0)
"""


def oscillator(inertia, stiffness, omega0):
    """A single body on a torsional spring to ground, at its rest angle with speed omega0."""
    body = Body("rotor", mass=1.0, inertia=inertia, joint=FIXED, rotation=ANGLE_SPRING, theta0=0.0, omega0=omega0,
                torsional_stiffness=stiffness)
    return Model(bodies=[body], meshes=[], tables=pack_gears([]), length_scale=1.0)


def angles(model, t_end, h, alpha):
    """Angles after every step; h a power of 2, so that the step times add up exactly (no
    sub-step to close a rounding gap)."""
    r = simulate(model, t_end, h, 1, alpha=alpha, tol=1e-14, max_newton=4)
    assert r.steps == r.nsteps and r.rejected == 0
    return r.body[:, 0, 2]


def amplification(Omega, alpha):
    """HHT-alpha amplification matrix of x'' + w^2 x = 0 for (x, h v, h^2 a), Omega = w h:
    a_{n+1} + (1 + alpha) w^2 x_{n+1} - alpha w^2 x_n = 0 with the Newmark updates."""
    beta, gamma = 0.25 * (1 - alpha) ** 2, 0.5 - alpha
    W2 = Omega**2
    ra = np.array([-W2, -(1 + alpha) * W2, -(1 + alpha) * W2 * (0.5 - beta)]) / (1 + (1 + alpha) * beta * W2)
    return np.array([np.array([1.0, 1.0, 0.5 - beta]) + beta * ra, np.array([0.0, 1.0, 1.0 - gamma]) + gamma * ra, ra])


def decay_per_step(x, skip, order):
    """Largest root modulus of the linear recurrence x_{n+p} = c_1 x_{n+p-1} + ... + c_p x_n
    fitted (least squares) to the samples x_n of a free vibration from step ``skip``: the
    amplification per step of the slowest-decaying mode. ``order`` 2 once the spurious root
    has died out, 3 (the whole characteristic polynomial) while it has not."""
    x = np.asarray(x)[skip:]
    m = len(x) - order
    A = np.column_stack([x[order - 1 - i:order - 1 - i + m] for i in range(order)])
    c = np.linalg.lstsq(A, x[order:], rcond=None)[0]
    return np.abs(np.roots(np.concatenate([[1.0], -c]))).max()


# ----------------------------------------------------------------------------- tables
def test_rigid_model_passes_an_empty_flex_table_of_the_compiled_signature():
    rigid = oscillator(2.0, 2e4, 1.0).pack()
    assert isinstance(rigid, KernelModel)
    for name, a in zip(FlexTable._fields, rigid.flex):
        assert a.ndim == 1 and len(a) == 0, name
    assert (rigid.bodies.flex == -1).all()
    assert rigid.compliant is None  # no compliant mesh: the rigid specialisation
    # a flexible body (a 4-tooth gear, 2 condensed modes, 4 table radii) fills the same fields
    # with data: the numba type, hence the compiled kernel, is the same
    from flexgear.dynamics.model.bodies import FlexBody, pack_flex

    flex = pack_flex([FlexBody(body=0, radius=np.arange(4.0), shape=np.ones((4, 2, 4, 2)),
                               self_compliance=np.ones((1, 2, 4)), coupling=np.ones((1, 2, 2, 4, 4)),
                               condensed_omega=np.ones(2))])
    assert numba.typeof(rigid._replace(flex=flex)) == numba.typeof(rigid)
    assert numba.typeof(empty_flex()) == numba.typeof(flex)


def test_the_rigid_specialisation_does_not_compile_the_compliant_contact_problem():
    """Exactly two specialisations of the model type: ``compliant`` None (no compliant mesh) and
    a FlexTable (every flexible model, whatever its size); the rigid one's force kernel is
    compiled without :func:`compliant_contacts` (numba prunes the branch on the None argument)."""
    from flexgear.config import load_config
    from flexgear.dynamics.contact.laws import LAW_HERTZ
    from flexgear.dynamics.integrator.forces import forces
    from flexgear.dynamics.integrator.simulation import evaluate
    from flexgear.dynamics.model.assembly import build_model

    models = {name: build_model(load_config(name)) for name in ("spur_pair", "spur_pair_flexible")}
    rigid, flexible = (models[n].pack() for n in ("spur_pair", "spur_pair_flexible"))
    assert (flexible.meshes.law == LAW_HERTZ).any() and flexible.compliant is flexible.flex
    assert rigid.compliant is None
    assert numba.typeof(rigid) != numba.typeof(flexible)
    assert numba.typeof(rigid._replace(compliant=flexible.flex)) == numba.typeof(flexible)

    def defined(name):  # the functions the force kernel's code defines for this model's type
        model = models[name]
        evaluate(model, *model.initial_state())
        kind = numba.typeof(model.pack())
        sig = next(s for s in forces.overloads if s[3] == kind)
        module = forces.overloads[sig].library._get_module_for_linking()  # compiled or loaded alike
        return " ".join(f.name for f in module.functions if not f.is_declaration)

    # the functions' names carry the kernels' qualified names: the rigid code has no compliant part
    assert "compliant_contacts" not in defined("spur_pair") and "mesh_search" in defined("spur_pair")
    assert "compliant_contacts" in defined("spur_pair_flexible")


def test_a_rigid_time_loop_is_compiled_without_one_pass_steps_and_flexible_modes():
    """A model without a compliant mesh iterates each step fully and has no flexible gear, so its
    time loop is compiled without :func:`linearised_acceptance` and the condensed modes' kernels
    (it tests its ``compliant`` argument, ``model.compliant``, against None; the modal
    coordinates' drive torque stays: a flexible gear without a mesh has them); a flexible
    model's time loop holds them. Asking a rigid model for one-pass steps is
    refused by name before anything compiles."""
    from flexgear.config import load_config
    from flexgear.dynamics.integrator.simulation import simulate
    from flexgear.dynamics.integrator.time_loop import integrate
    from flexgear.dynamics.model.assembly import build_model

    def defined(name):  # the functions the time loop's code defines for this model's type
        cfg = load_config(name)
        model = build_model(cfg)
        h = cfg.simulation["step"]
        simulate(model, 8 * h, h, 8)
        kind = numba.typeof(model.pack())
        sig = next(s for s in integrate.overloads if s[5] == kind)
        module = integrate.overloads[sig].library._get_module_for_linking()
        return model, " ".join(f.name for f in module.functions if not f.is_declaration)

    # the condensed modes' other kernels (start_condensed, accept_condensed, ...) are small enough
    # that LLVM inlines them and drops their names; record_condensed keeps its name in both
    flexible_only = ("linearised_acceptance", "record_condensed")
    rigid, code = defined("spur_pair")
    assert "newton_update" in code
    assert not [f for f in flexible_only if f in code]
    code = defined("spur_pair_flexible")[1]
    assert [f for f in flexible_only if f not in code] == []
    with pytest.raises(ValueError, match="one_pass = True"):
        simulate(rigid, 1e-4, 1e-5, 1, one_pass=True)


def test_a_gear_model_and_a_model_without_gears_share_the_compiled_signature():
    from flexgear.config import load_config
    from flexgear.dynamics.model.assembly import build_model

    gears = build_model(load_config("spur_pair"))
    plain = oscillator(2.0, 2e4, 1.0)
    assert numba.typeof(gears.pack()) == numba.typeof(plain.pack())
    assert numba.typeof(gears.tables) == numba.typeof(plain.tables)
    assert len(plain.tables.gear_z) == 0 and plain.tables.outlines.shape == (0, 2)


def test_a_second_process_loads_the_kernels_from_the_disk_cache():
    simulate(oscillator(2.0, 2e4, 1.0), 0.01, 1e-3, 1)  # compiles here (and writes the cache) if needed
    assert compiled_cache_present()
    script = OSCILLATOR + """
import json
from flexgear.dynamics.integrator.forces import forces
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.dynamics.integrator.time_loop import integrate
simulate(oscillator(2.0, 2e4, 1.0), 0.01, 1e-3, 1)
print(json.dumps({k: [sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values())]
                  for k, f in (("forces", forces), ("integrate", integrate))}))
"""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=600,
                         cwd=ROOT)
    assert out.returncode == 0, out.stderr
    counts = json.loads(out.stdout.strip().splitlines()[-1])
    for name, (hits, misses) in counts.items():
        assert hits >= 1 and misses == 0, f"{name}: {hits} cache hits, {misses} misses"


# ----------------------------------------------------------------------------- HHT-alpha
def test_hht_is_second_order_accurate():
    inertia, k, w0 = 2.0, 2e4, 1.0
    w = math.sqrt(k / inertia)  # 100 rad/s
    T = 0.25  # four periods
    errors = []
    for h in (2.0**-9, 2.0**-10, 2.0**-11):  # w h = 0.2, 0.1, 0.05
        th = angles(oscillator(inertia, k, w0), T, h, -0.1)
        t = h * np.arange(1, len(th) + 1)
        errors.append(np.max(np.abs(th - w0 / w * np.sin(w * t))))
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(3.6 < r < 4.4 for r in ratios), f"error ratios per step halving {ratios} (expected ~4)"


@pytest.mark.parametrize("alpha", [0.0, -0.1, -0.3])
def test_hht_numerical_damping_per_step_matches_its_spectral_radius(alpha):
    inertia, h = 2.0, 2.0**-7
    k = inertia / h**2  # w h = 1
    th = angles(oscillator(inertia, k, 1.0), 1.0, h, alpha)
    lam = np.linalg.eigvals(amplification(1.0, alpha))
    rho = np.sort(np.abs(lam))[-1]  # principal pair; the spurious root dies out in the 20 skipped steps
    assert np.sort(np.abs(lam))[0] < 0.05
    assert decay_per_step(th, 20, 2) == pytest.approx(rho, abs=1e-7)
    if alpha == 0.0:
        assert rho == pytest.approx(1.0, abs=1e-12)  # trapezoidal rule: no numerical damping
    else:
        assert 1 - rho > 1e-3  # a damping the check can see


@pytest.mark.parametrize("alpha", [-0.1, -0.3])
def test_hht_damps_high_frequencies_by_its_asymptotic_spectral_radius(alpha):
    inertia, h = 2.0, 2.0**-7
    k = inertia * (1e4 / h) ** 2  # w h = 10^4
    th = angles(oscillator(inertia, k, 1.0), 40 * h, h, alpha)
    rho = decay_per_step(th, 0, 3)
    assert rho == pytest.approx(np.abs(np.linalg.eigvals(amplification(1e4, alpha))).max(), abs=2e-6)
    assert rho == pytest.approx((1 + alpha) / (1 - alpha), abs=1e-5)
