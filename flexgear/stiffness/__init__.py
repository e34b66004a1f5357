"""Tooth and mesh stiffness of spur gears from plane finite elements plus Hertzian contact.

Layer 4 (``gears -> fe -> stiffness``). Modules: :mod:`.hertz` (closed forms), :mod:`.compliance`
(one tooth, FE), :mod:`.loaded_mesh` (a pair), :mod:`.iso_comparison` and :mod:`.iso6336`
(ISO 6336-1), :mod:`.compliance3d` (3D vs plane models), :mod:`.fe_convergence`, :mod:`.impact_fit`
(an IMPACT law fitted to the loaded-mesh transmission error, for rigid models), :mod:`.crack` (a tooth
with a root crack: single-pair stiffness, rigid-model representations; docs/theory/crack.md),
:mod:`.crack_energy` (the published potential-energy crack model it is compared with) and
:mod:`.crack3d` (a crack over part of the face width, 3D against plane slices). Compared with ISO 6336-1 in
:mod:`flexgear.stiffness.iso6336`; the command ``python -m flexgear.stiffness`` prints the comparison
for the MERCURY 1-A sun-planet and planet-ring pairs.

Method
------
**1. Tooth compliance (one gear, FE).** The gear body is meshed (:func:`flexgear.fe.meshing.mesh_gear`),
clamped at its bore (``"hub"``, external gears) or at its outer rim (``"rim"``, the ring) and
loaded on the left flank of tooth 0 at a contact point P of radius r, normal to the flank (the
normal of an involute lies along the line of action). A point load in 2D gives a displacement
that grows like ln(1/h) under refinement, so the load is *spread* over a smooth patch of the
flank centred on P::

    p(s) ~ (1 - s^2/w^2)^2   for |s| < w      (s: arc length along the involute from P)

with half-width ``w = spread * m`` (default 0.5 m), normalised to a unit resultant. The
displacement is measured work-conjugately, as the p-weighted mean of the normal displacement
over the same patch (``u_P = f_P . u`` with ``f_P`` the load vector), which makes the influence
matrix symmetric (Maxwell-Betti).

**2. Near field separated analytically.** The FE response to the patch load contains the
half-plane (Flamant) near field of that patch, which depends on w (logarithmically). It is
subtracted in closed form: for a pressure distribution p on a straight half-plane boundary
(Young's modulus and Poisson's ratio of the formulation, ``E1, nu1``: plane stress E, nu; plane
strain E/(1-nu^2), nu/(1-nu)), the p-weighted mean normal displacement of the loaded surface
relative to the point at depth d below the patch centre is, per unit resultant F [N] on a body
of thickness L::

    u_loc = 1/(pi E1 L) * [ 2 (ln d - J) - (1 + nu1) ],    J = int int p^ p^ ln|s - t| ds dt

(p^ = p/F normalised; derived from Flamant's displacement field; J = ln(w/2) - 1/4 for the
elliptical Hertz pressure, computed numerically for the patch, also when the patch is clipped at
the end of the flank). The remainder ``c_bulk = c_FE - u_loc`` (tooth bending, shear, rim and
body deformation up to the reference depth) does not depend on w for w small against the tooth
(checked by a test) and converges under mesh refinement.

**3. Hertzian contact, nonlinear.** Two teeth pressed together by F (per thickness P = F/L)
carry the elliptical Hertz pressure of half-width ``a = sqrt(4 P R / (pi E*))``, R the relative
radius of curvature of the involutes at the contact (rho_i = distance of the contact from the
base tangent point; R = rho1 rho2/(rho1 + rho2), internal rho1 rho2/(rho2 - rho1)). Using the
same weighted-mean displacement for the contact and the half-plane solution above with J of the
ellipse, the approach of the two reference points (depth d_i in each tooth) is, exactly for
2D Hertz line contact (the conformity condition adds a^2 / (8 R))::

    delta_H(F) = sum_i P/(pi E1_i) [2 ln(2 d_i / a) - 1/2 - nu1_i] + P / (2 pi E*)

(Weber/Johnson form; nonlinear in F through a ~ sqrt(F)). The contact zone is narrow against
the face width, so the Hertz term is taken in **plane strain** (``hertz="plane_strain"``) while
the FE body may be plane stress (the project default): the region within depth d = m of the
contact is treated as plane strain. ``hertz="same"`` uses the FE formulation (then d cancels
exactly); for the MERCURY pairs the two choices differ by 2-3 % in c'.

**4. Loaded mesh.** For a :class:`~flexgear.gears.geometry.GearPair`, contact positions are measured
along the line of action by s (from the pitch point, positive towards the tip of gear 1),
s in [-g_f, g_a]; pairs in contact at one instant are s, s + p_b, s + 2 p_b, ... within that
path (perfect involutes, no modifications; contact outside the path: step 5). Each gear
is solved once per pair: unit patch loads on tooth 0 at all grid points, displacements read on
teeth -N ... +N (N = the most pairs at once minus 1, at least 1) give the influence matrices,
including the coupling between loaded teeth of the same gear that many teeth apart. The static transmission error (along the line of action) delta
and the pair loads F_k follow from compatibility and equilibrium::

    delta = sum_l [C1_kl + C2_kl] F_l + delta_H,k(F_k)  for every loaded pair k,   sum_k F_k = F

solved by iterating on the secant Hertz compliance (a pair that would pull is unloaded).
Mesh stiffness k(s) = F / delta [N/m] (secant); single-pair stiffness k'(s) = F / (C1_kk +
C2_kk + delta_H(F)/F) for one pair carrying the whole load. ISO's c' is compared with
max_s k'(s) / b and c_gamma_alpha with the mean of k over one mesh cycle, divided by b.

**5. Contact outside the path (option ``extended=True``).** Under load the deflected teeth
close gaps the rigid outlines leave open: the approaching tooth's tip corner meets the mate's
flank before the path starts, the leaving pair stays in contact after it ends. A pair at s
outside the path has the no-load separation ``e(s)`` of its tip corner from the mate's involute
(:func:`~.loaded_mesh.tip_separation`, in closed form: involutes of one base circle are
parallel curves, so a point's distance from a flank along its normal is r_b times the
difference of ``phi + inv(alpha_r)``); with gear 1 held and gear 2 turning (the driven, loaded
gear), the compatibility and equilibrium become::

    arm_k (delta - e_k) = sum_l C_kl F_l + delta_H,k(F_k)   (loaded pairs),   sum_k arm_k F_k = F

with ``arm_k`` the moment arm of the contact normal about gear 2 over r_b2 (1 on the path).
The default is the path only (ISO's model, used for the ISO comparison and the lumped model);
for the MERCURY sun-planet pair under 200 N m the extension raises the share of two loaded pairs
from eps_alpha - 1 = 0.59 to 0.79 and lowers the mean transmission error by 4 %. The extension
ends where the separation exceeds ``max_gap`` (0.1 m), where the corner leaves the mate's
involute or at a base circle; it may bring up to ``max_pairs`` (4) pairs within reach at once,
coupled through the tables of their tooth distances: the MERCURY planet-ring pair (eps_alpha
1.73) carries a third pair, two teeth from the first, at 10 kN per mesh (mean 2.08 loaded pairs,
transmission error 10 % below the path-only one).

All quantities SI: m, N, N/m; compliances m/N; stiffness per face width N/m^2.
"""
