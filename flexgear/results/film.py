"""EHL film thickness of every recorded tooth contact of a lubricated run, computed from the result.

For each contact slot of ``sliding_speed`` (rigid: the contact slots of ``pair_force``; lumped:
the pairs on the path of contact) at contact position s [m] from the pitch point (positive
towards the tip of gear a):

* radii of curvature of the involutes rho_a = r_b,a tan(alpha_w) + s, rho_b = r_b,b tan(alpha_w)
  - s (internal gear b: + s), relative radius R = rho_a rho_b / (rho_b + rho_a) (internal:
  rho_a rho_b / (rho_b - rho_a));
* entrainment speed u_e = (|omega_a| rho_a + |omega_b| rho_b) / 2, omega relative to the frame
  the centres stand still in (the carrier), from the recorded angular velocities;
* load per face width w = N / b: N the slot's normal force (rigid: ``pair_force``; lumped: the
  mesh force shared equally by the pairs on the path of contact, as the friction is, when the
  drive flanks are in contact);
* central and minimum film thickness h_c, h_min of
  :func:`~flexgear.gears.tribology.central_film_thickness` (Dowson & Toyoda 1979) and
  :func:`~flexgear.gears.tribology.minimum_film_thickness` (Dowson & Higginson 1977), and the
  film thickness ratio lambda = h_min / sigma (sigma the mesh's composite RMS roughness; nan
  without a configured roughness, inf for a roughness of 0).

nan where a slot holds no loaded contact (no pair, N <= 0, R <= 0). Post-processing only: the
solver is not involved. Guide page *Lubrication*, section *Film thickness outputs*.
"""
from __future__ import annotations

import math

import numpy as np

from ..config.faults import mesh_pairs
from ..gears.material import effective_modulus
from ..gears.tribology import central_film_thickness, minimum_film_thickness
from ..kernels import kernel


def slot_loads(model: str, signals) -> np.ndarray:
    """(n, P) normal force [N] of each contact slot of ``signals.sliding_speed`` (a
    :class:`~flexgear.results.store.MeshSignals` with friction outputs) of a run of ``model``
    (``"rigid"`` or ``"lumped"``; module docstring); 0 where there is no pair."""
    s = signals.contact_position
    on = np.isfinite(s)
    if model == "lumped":
        count = np.maximum(on.sum(axis=1, keepdims=True), 1)
        drive = signals.pair_side[:, :1] > 0  # the drive flanks carry the mesh force (back flank: -1)
        mesh = np.where(drive, np.maximum(signals.pair_force[:, :1], 0.0), 0.0)
        return np.where(on, mesh / count, 0.0)
    return np.where(on, np.maximum(signals.pair_force[:, :s.shape[1]], 0.0), 0.0)


def contact_geometry(pair, s, omega_a, omega_b):
    """Relative radius of curvature R [m] and entrainment speed u_e [m/s] of contacts at
    positions ``s`` [m] of the GearPair ``pair`` turning at ``omega_a``, ``omega_b`` [rad/s]
    relative to the frame (module docstring); arrays broadcast."""
    tw = math.tan(pair.alpha_w)
    sig = -1.0 if pair.internal else 1.0
    rho_a = pair.g1.rb * tw + s
    rho_b = pair.g2.rb * tw - sig * s
    R = rho_a * rho_b / (rho_b + sig * rho_a)
    ue = 0.5 * (np.abs(omega_a) * rho_a + np.abs(omega_b) * rho_b)
    return R, ue


@kernel(error_model="numpy")
def film_thicknesses(u_e, w, R, eta, alpha, e_star, central, minimum):
    """Central and minimum film thickness [m] (:func:`~flexgear.gears.tribology.central_film_thickness`,
    :func:`~flexgear.gears.tribology.minimum_film_thickness`) of the contacts of flat arrays
    ``u_e`` [m/s], ``w`` [N/m], ``R`` [m] into ``central``, ``minimum``: the kernels in one
    compiled loop, not a dispatcher call per contact."""
    for i in range(u_e.shape[0]):
        central[i] = central_film_thickness(u_e[i], eta, alpha, w[i], R[i], e_star)
        minimum[i] = minimum_film_thickness(u_e[i], eta, alpha, w[i], R[i], e_star)


def film_outputs(cfg, result) -> None:
    """Set ``film_central``, ``film_minimum`` [m] and ``film_ratio`` [-] (lambda; nan without a
    roughness) of every mesh of ``result`` that has friction outputs, when ``cfg.lubrication``
    names a lubricant (module docstring); nothing otherwise."""
    lub = cfg.lubrication
    if lub is None or lub.lubricant is None:
        return
    eta, alpha = lub.lubricant.viscosity, lub.lubricant.pressure_viscosity
    e_star = effective_modulus(cfg.material, cfg.material)
    pairs = mesh_pairs(cfg)
    frame = result.bodies.get("carrier")
    w_f = frame.angular_velocity if frame is not None else 0.0
    model = result.attrs.get("model", cfg.model)
    for name, sig in result.meshes.items():
        if sig.contact_position is None:
            continue
        an, bn, pair = pairs[name]
        wa = (result.bodies[an].angular_velocity - w_f)[:, None]
        wb = (result.bodies[bn].angular_velocity - w_f)[:, None]
        s = sig.contact_position
        N = slot_loads(model, sig)
        R, ue = contact_geometry(pair, np.where(np.isfinite(s), s, 0.0), wa, wb)
        ok = (N > 0.0) & (R > 0.0) & (ue > 0.0)
        u, R = (np.broadcast_to(x, N.shape)[ok] for x in (ue, R))  # the loaded contacts only
        central, minimum = np.empty(u.size), np.empty(u.size)
        film_thicknesses(u, N[ok] / pair.face_width, R, float(eta), float(alpha), float(e_star), central, minimum)
        hc, hm = np.full(N.shape, np.nan), np.full(N.shape, np.nan)
        hc[ok], hm[ok] = central, minimum
        rough = lub.mesh_roughness(pair.g1.name, pair.g2.name)
        sig.film_central = hc
        sig.film_minimum = hm
        with np.errstate(divide="ignore"):
            sig.film_ratio = hm / rough if rough is not None else np.full_like(hm, np.nan)
