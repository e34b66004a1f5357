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

nan where a slot holds no loaded contact (no pair, N <= 0, R <= 0) and where the contact lies
outside the involute of either flank, s outside
:func:`~flexgear.gears.lubrication.involute_contact_limits` (the ISO path of contact; a tip
corner touching the mating flank, as the soft contact of the rigid model and the compliant
flexible teeth make them): there the involute radius of curvature extrapolated past the tip,
or below the form circle, is no radius of the bodies in contact, and a sharp corner has no
line-contact EHL film. The number of loaded contact samples so left out is recorded per mesh
(``film_corner_contacts``), so the least film of a run is that of the involute contacts.
Post-processing only: the solver is not involved. Guide page *Lubrication*, section *Film
thickness outputs*.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..config.faults import mesh_pairs
from ..gears.lubrication import involute_contact_limits
from ..gears.material import effective_modulus
from ..gears.tribology import central_film_thickness, minimum_film_thickness
from ..kernels import kernel


class FilmMesh(NamedTuple):
    """The constants of one mesh's film outputs (module docstring): the arms at the pitch point
    r_b tan(alpha_w) of gear a and gear b [m], sigma (+1 external, -1 internal gear b), the face
    width in contact [m], the lubricant's viscosity [Pa s] and pressure-viscosity coefficient
    [1/Pa], the pair's Hertz modulus E* [Pa], and the positions [m] between which both flanks
    are involute (:func:`~flexgear.gears.lubrication.involute_contact_limits`)."""

    arm_a: float
    arm_b: float
    sigma: float
    width: float
    eta: float
    alpha: float
    e_star: float
    start: float
    end: float


#: [m] a contact this close outside the involute limits is at the tip, not past it (rounding)
LIMIT_TOLERANCE = 1e-9


def film_mesh(pair, eta: float, alpha: float, e_star: float) -> FilmMesh:
    """The :class:`FilmMesh` of the GearPair ``pair`` (its face width in contact)."""
    tw = math.tan(pair.alpha_w)
    start, end = involute_contact_limits(pair)
    return FilmMesh(pair.g1.rb * tw, pair.g2.rb * tw, -1.0 if pair.internal else 1.0, float(pair.face_width),
                    float(eta), float(alpha), float(e_star), start - LIMIT_TOLERANCE, end + LIMIT_TOLERANCE)


@kernel(error_model="numpy")
def film_slots(position, force, side, omega_a, omega_b, mesh, lumped, central, minimum):
    """Central and minimum film thickness [m] of every contact slot into ``central``,
    ``minimum`` (n, P) (nan: no loaded contact, or a loaded contact outside the involutes), in
    one compiled pass (module docstring); returns the number of loaded contacts outside the
    involutes (tip corners), left without a film:
    ``position`` (n, P) the contact positions [m] (nan: no pair), ``force``, ``side`` the
    mesh's ``pair_force`` [N] and ``pair_side`` (``lumped``: column 0 holds the mesh force and
    its flank, shared by the pairs on the path when the drive flanks touch; otherwise the slot's
    own normal force), ``omega_a``, ``omega_b`` (n,) the gears' speeds relative to the frame
    [rad/s], ``mesh`` a :class:`FilmMesh`."""
    n, slots = position.shape
    corners = 0
    for i in range(n):
        share = 0.0
        if lumped:
            count = 0
            for j in range(slots):
                if math.isfinite(position[i, j]):
                    count += 1
            if side[i, 0] > 0 and force[i, 0] > 0.0:
                share = force[i, 0] / max(count, 1)
        wa = abs(omega_a[i])
        wb = abs(omega_b[i])
        for j in range(slots):
            central[i, j] = np.nan
            minimum[i, j] = np.nan
            s = position[i, j]
            if not math.isfinite(s):
                continue
            N = share if lumped else max(force[i, j], 0.0)
            rho_a = mesh.arm_a + s
            rho_b = mesh.arm_b - mesh.sigma * s
            R = rho_a * rho_b / (rho_b + mesh.sigma * rho_a)
            ue = 0.5 * (wa * rho_a + wb * rho_b)
            if N > 0.0 and not mesh.start <= s <= mesh.end:
                corners += 1  # a tip corner on the mating flank: no involute line contact
                continue
            if N > 0.0 and R > 0.0 and ue > 0.0:
                w = N / mesh.width
                central[i, j] = central_film_thickness(ue, mesh.eta, mesh.alpha, w, R, mesh.e_star)
                minimum[i, j] = minimum_film_thickness(ue, mesh.eta, mesh.alpha, w, R, mesh.e_star)
    return corners


def film_outputs(cfg, result) -> None:
    """Set ``film_central``, ``film_minimum`` [m] and ``film_ratio`` [-] (lambda; nan without a
    roughness) of every mesh of ``result`` that has friction outputs, when ``cfg.lubrication``
    names a lubricant (module docstring), and the mesh attributes they come from:
    ``film_viscosity`` eta_0 [Pa s] at the oil temperature, ``film_pressure_viscosity`` alpha
    [1/Pa], ``film_effective_modulus`` E* [Pa] (Hertz, 1/E* = sum (1 - nu^2)/E) and
    ``film_roughness``, the mesh's composite RMS roughness [m] (None: not given),
    ``film_involute_limits`` [m], the positions between which both flanks are involute (the
    film is computed there only), and ``film_corner_contacts``, the number of loaded contact
    samples (slots times output samples) outside them, left without a film; nothing
    otherwise."""
    lub = cfg.lubrication
    if lub is None or lub.lubricant is None:
        return
    eta, alpha = lub.lubricant.viscosity, lub.lubricant.pressure_viscosity
    e_star = effective_modulus(cfg.material, cfg.material)
    pairs = mesh_pairs(cfg)
    frame = result.bodies.get("carrier")
    w_f = frame.angular_velocity if frame is not None else 0.0
    lumped = result.attrs.get("model", cfg.model) == "lumped"
    for name, sig in result.meshes.items():
        if sig.contact_position is None:
            continue
        an, bn, pair = pairs[name]
        wa = np.ascontiguousarray(result.bodies[an].angular_velocity - w_f, dtype=float)
        wb = np.ascontiguousarray(result.bodies[bn].angular_velocity - w_f, dtype=float)
        s = np.ascontiguousarray(sig.contact_position, dtype=float)
        hc, hm = np.empty(s.shape), np.empty(s.shape)
        fm = film_mesh(pair, eta, alpha, e_star)
        corners = film_slots(s, np.ascontiguousarray(sig.pair_force, dtype=float), np.ascontiguousarray(sig.pair_side),
                             wa, wb, fm, lumped, hc, hm)
        rough = lub.mesh_roughness(pair.g1.name, pair.g2.name)
        # what the film was computed from, for a check by hand (SI; roughness None: not given)
        sig.attrs.update(film_viscosity=float(eta), film_pressure_viscosity=float(alpha),
                         film_effective_modulus=float(e_star), film_roughness=rough,
                         film_involute_limits=[float(x) for x in involute_contact_limits(pair)],
                         film_corner_contacts=int(corners))
        sig.film_central = hc
        sig.film_minimum = hm
        with np.errstate(divide="ignore"):
            sig.film_ratio = hm / rough if rough is not None else np.full_like(hm, np.nan)
