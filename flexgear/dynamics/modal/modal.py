"""Linearised modal analysis: natural frequencies, mass-normalised mode shapes, modal energies and
the mode type of a gear set.

A linear system is a mass matrix and a list of springs (or explicit K and M, see below). A spring (gear mesh, bearing, support)
has a stiffness k and a gradient g: its deflection is g . q, so K = sum_s k_s g_s g_s^T and the
strain energy of a mode phi in the spring is k_s (g_s . phi)^2 / 2. Bodies carry a pose
Jacobian J_b (3 x n: x, y, theta in the global frame) and their mass and inertia, so
M = sum_b J_b^T diag(m_b, m_b, I_b) J_b and the kinetic energy of a mode in a body is
phi^T J_b^T diag(m, m, I) J_b phi / 2 (times omega^2).

Three sources build such systems:

* :func:`linearise` - the rigid model (:mod:`flexgear.dynamics.model.assembly`) about its loaded
  operating point. The static equilibrium under the load torque is solved at positions spread
  over one mesh cycle (the driven body held at each position, the others free); each mesh's
  stiffness is the tangent of the IMPACT law, k = sum_c K e delta_c^(e-1) over its loaded tooth
  pairs, averaged over the cycle; its direction is the line of action of the loaded contacts.
  Bearings and supports enter with their stiffness. Speed effects (centripetal, gyroscopic)
  are left out, as in Lin & Parker's stationary analysis.
* :func:`linearise` of a flexible model (meshes with the compliant Hertz law of
  :mod:`flexgear.dynamics.flexible.compliant`, modal coordinates of :mod:`flexgear.dynamics.flexible.floating_frame`, elastic shafts): the same
  equilibria over a mesh cycle, but K is the solver's own tangent stiffness
  (:func:`~flexgear.dynamics.integrator.simulation.evaluate`), symmetrised and averaged over the cycle: the
  joint tangent (C + diag h')^-1 of all compliant contacts (so the coupling between meshes
  through a gear's rim is in it), bearings, shafts, the modal stiffness omega_i^2 and the
  modes' share of every contact's approach; M is the solver's Mq (the frame-mode inertia
  coupling included) plus -dQ/dq'' of the contact forces through the flanks' deflection under
  the gears' own inertia load (condensed modes, :func:`~flexgear.dynamics.flexible.compliant.inertia_flank_value`;
  symmetrised, ``attrs["inertia_relief_mass"]``): a gear the mesh accelerates is stiffer at
  its flanks than with its bore held (spur pair: the mesh mode 7.6 % higher). The condensed
  modes (between ``[flexible] dynamic_cutoff`` and ``cutoff``) enter as the solver integrates
  them (``condensation``, as in :func:`~flexgear.dynamics.integrator.simulation.simulate`): ``"integrated"``
  (the default) carries their own inertia, which is the same as having every mode a coordinate
  (:mod:`flexgear.dynamics.flexible.condensed`), so the linearisation makes each of them a modal coordinate
  (:func:`modes_as_coordinates`: the reduced model's modal mass, stiffness omega_i^2 and
  frame-mode coupling, their flank displacement in the contact tangent, no inertia relief
  left); ``"static"`` condenses them quasi-statically as above. Each matches a free vibration
  of the integrator with the same condensation; at one mesh position the static condensation
  puts the flexible spur pair's mesh mode 1.6 % below the integrated one, MERCURY 1-A's mesh
  modes 0.4-0.7 % below, and the coupled mode of a soft gear whose condensed modes the mesh
  excites (modulus x 0.01, modes at 3-10 kHz) 7 % above. The system carries these as explicit matrices
  (:attr:`LinearSystem.stiffness`, :attr:`LinearSystem.mass`); its springs then only split the
  strain energy: each mesh a spring along the line of action of its loaded drive-side contacts
  with the mesh's own stiffness (the other meshes' approaches held, fitted to the contact
  tangent: :func:`_mesh_decomposition`), each modal coordinate a spring omega_i^2; the part of K
  they leave (contact coupling between meshes, back-flank contacts) is the strain-energy entry
  :data:`COUPLING`. With ``free_drive`` the set's kinematic rotation is projected out of K (a
  tip-corner contact's moment arms off r_b1 : r_b2 resist it at some positions and drive it at
  others). Checked in ``tests/test_flexible_modal.py``: the spur pair's mesh mode against the
  FE loaded mesh's tangent stiffness with the static FE inertia relief (0.2-0.6 %), a shaft chain built by hand, a soft gear's
  coupled mode against a free vibration of the same model, MERCURY 1-A against Lin & Parker
  with the same mesh stiffnesses (the coupling between meshes moves the modes by up to 2 %).
* :mod:`flexgear.dynamics.lumped.planetary` - published lumped-parameter models set up from explicit
  parameters (Lin & Parker's planar planetary model).

A simulation shows a mode where its HHT-alpha step puts it, not at f_n:
:func:`integrated_frequency` (at 25 us an 8.9 kHz mode rings at 7.6 kHz, at the flexible
presets' 6.25 us at 8.79 kHz), so spectral peaks are matched to those values.

Mode types (Lin & Parker 1999, equally spaced planets). The system is invariant under the
rotation by 2 pi / N that moves planet n to planet n + 1 and turns the central members'
translations by 2 pi / N. Each mode lies in one harmonic j (0 .. N-1) of that cyclic group:
j = 0 rotational modes (central members rotate, do not translate; multiplicity 1), j = +-1
translational modes (central members translate, do not rotate; multiplicity 2), all other j
planet modes (central members still; multiplicity N - 3). Where the central members have no
translational coordinate (planets on rigid pins, purely torsional models) the j = +-1 modes
keep the central members still too and are planet modes (multiplicity N - 1). The type is
computed from the mode's energy in each harmonic, so it can be checked, not only printed.
"""
from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..integrator.simulation import CONDENSATION, evaluate
from ..contact.laws import LAW_HERTZ
from ..model.bodies import ANGLE_FREE, ANGLE_PRESCRIBED, ANGLE_SPRING, BEARING, FlexBody, Model, Profile
from ..flexible.reductions import check_frame_inertia
from ...errors import ConfigError

ROTATIONAL, TRANSLATIONAL, PLANET, UNCLASSIFIED = "rotational", "translational", "planet", "-"
#: Strain-energy entry of an explicit stiffness matrix not represented by the springs.
COUPLING = "coupling (K - springs)"

# a position where a contact switches on and off between Newton iterations (a tooth corner
# entering, found by the contact search only on one side of a threshold) has no exact
# equilibrium; the best state is kept if its force residual is below this fraction of the load
# (listed in the system's attrs), else the position is skipped; more than a quarter of the
# positions skipped is an error
APPROXIMATE_EQUILIBRIUM = 0.3


@dataclass
class Spring:
    """A linear spring of a linearised gear set.

    Attributes
    ----------
    name : str
        e.g. ``"sun-planet1"``, ``"planet1 bearing x"``, ``"ring torsion"``.
    kind : str
        ``"mesh"``, ``"bearing"``, ``"support"`` or ``"shaft"`` (:mod:`flexgear.dynamics.model.shafts`).
    k : float
        Stiffness [N/m, or N m/rad for a torsional spring on an angle coordinate].
    g : ndarray (n,)
        Deflection per unit generalised coordinate [m/m, m/rad or rad/rad].
    """

    name: str
    kind: str
    k: float
    g: np.ndarray


@dataclass
class LinearSystem:
    """Mass matrix, springs and bodies of a linearised gear set.

    Attributes
    ----------
    dofs : list of str
        Coordinate names (``body.x``, ``body.theta``, ``planet1.zeta`` ...).
    bodies : dict name -> (mass [kg], inertia [kg m^2], J (3, n))
        Pose Jacobian J: global x, y [m] and rotation [rad] per unit coordinate.
    springs : list of Spring
    planets : list of str
        Planet body names in counter-clockwise order (empty for a spur pair).
    planet_angles : ndarray
        Angular positions of the planets [rad] (global frame).
    central : list of str
        Central members (sun, carrier, ring) that are bodies of the system.
    attrs : dict
        Where the system came from (operating point, mean mesh stiffness, ...).
    stiffness : ndarray (n, n), optional
        Explicit stiffness matrix. None (rigid model, lumped models): K = sum k g g^T of the
        springs. Given (flexible model: the solver's tangent, with the joint compliant-contact
        and modal stiffness), K is this matrix and the springs only split a mode's strain
        energy for the energy table; the part of K they do not represent (contact coupling
        across meshes, back flanks) appears as :data:`COUPLING` in the strain energies.
    mass : ndarray (n, n), optional
        Explicit mass matrix (flexible model: the solver's Mq, with the frame-mode coupling of
        the modal coordinates). None: M = sum J^T diag(m, m, I) J of the bodies.
    body_modes : dict name -> list of int
        Indices of each flexible body's modal coordinates (the kinetic energy of M - sum J^T
        diag J J in their rows is that body's).
    modal_rotation : dict name -> ndarray (m, m)
        For a central member with modal coordinates: T with eta' = T eta the coordinates of its
        displacement field turned by 2 pi / N (:func:`modal_rotation`). A central member with
        modal coordinates but no T leaves the system without a symmetry operator.
    """

    dofs: list
    bodies: dict
    springs: list
    planets: list = field(default_factory=list)
    planet_angles: np.ndarray = field(default_factory=lambda: np.zeros(0))
    central: list = field(default_factory=list)
    attrs: dict = field(default_factory=dict)
    stiffness: np.ndarray | None = None
    mass: np.ndarray | None = None
    body_modes: dict = field(default_factory=dict)
    modal_rotation: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.dofs)

    @property
    def rigid_mass(self) -> np.ndarray:
        """Mass matrix of the bodies' rigid motion, sum J^T diag(m, m, I) J [kg, kg m, kg m^2]."""
        M = np.zeros((self.n, self.n))
        for m, inertia, J in self.bodies.values():
            M += J.T @ np.diag([m, m, inertia]) @ J
        return M

    @property
    def M(self) -> np.ndarray:
        """Mass matrix [kg, kg m, kg m^2] (the explicit one when given)."""
        return self.rigid_mass if self.mass is None else self.mass

    @property
    def spring_stiffness(self) -> np.ndarray:
        """Stiffness matrix of the springs, sum k g g^T."""
        K = np.zeros((self.n, self.n))
        for s in self.springs:
            K += s.k * np.outer(s.g, s.g)
        return K

    @property
    def K(self) -> np.ndarray:
        """Stiffness matrix (the explicit one when given, else sum k g g^T)."""
        return self.spring_stiffness if self.stiffness is None else self.stiffness

    def symmetry_operator(self) -> np.ndarray | None:
        """The coordinate map P of the rotation by 2 pi / N (planet n -> n + 1), or None when the
        planets are not equally spaced (or fewer than 3)."""
        N = len(self.planets)
        if N < 3:
            return None
        step = 2 * math.pi / N
        d = np.diff(np.unwrap(np.asarray(self.planet_angles, float)))
        if np.any(np.abs(d - step) > 1e-6):
            return None
        c, s = math.cos(step), math.sin(step)
        index = {name: i for i, name in enumerate(self.dofs)}
        P = np.zeros((self.n, self.n))
        target = {p: self.planets[(k + 1) % N] for k, p in enumerate(self.planets)}
        for body, rows in self.body_modes.items():
            if body in target:
                continue
            # a central member's modes turn into combinations of each other (degenerate pairs)
            T = self.modal_rotation.get(body)
            if T is None:
                return None
            P[np.ix_(rows, rows)] = T
        for name, i in index.items():
            body, coord = name.rsplit(".", 1)
            dest = target.get(body, body)
            if body in self.modal_rotation and coord.startswith("eta"):
                continue
            if coord in ("x", "y"):
                ix, iy = index[f"{body}.x"], index[f"{body}.y"]
                jx, jy = index[f"{dest}.x"], index[f"{dest}.y"]
                if coord == "x":  # the x component goes to c x' and s y'
                    P[jx, ix] += c
                    P[jy, ix] += s
                else:
                    P[jx, iy] += -s
                    P[jy, iy] += c
            else:  # angles and body-frame coordinates (zeta, eta, u) move unchanged
                P[index[f"{dest}.{coord}"], i] = 1.0
        return P

    def has_central_translation(self) -> bool:
        """Whether any central member can translate (has a coordinate moving its centre)."""
        return any(np.any(self.bodies[c][2][:2] != 0.0) for c in self.central if c in self.bodies)


@dataclass
class ModalResult:
    """Natural frequencies and modes of a :class:`LinearSystem`.

    Attributes
    ----------
    frequencies : ndarray (n,)
        Natural frequencies [Hz], ascending (0 for rigid-body modes).
    shapes : ndarray (n, n)
        Mass-normalised mode shapes (columns): Phi^T M Phi = I.
    eigenvalues : ndarray (n,)
        omega^2 [rad^2/s^2].
    strain_energy : dict name -> ndarray (n,)
        Fraction of each mode's strain energy in each spring (sums to 1 per elastic mode).
    kinetic_energy : dict body -> ndarray (n,)
        Fraction of each mode's kinetic energy in each body.
    mode_type : list of str
        ``rotational``, ``translational``, ``planet`` or ``-`` (no cyclic symmetry).
    type_purity : ndarray (n,)
        Fraction of the mode's kinetic energy in the harmonics of its type (1 for an exact type).
    harmonic : ndarray (n,) int
        Dominant cyclic harmonic j (0 .. N-1), -1 without symmetry.
    multiplicity : ndarray (n,) int
        Number of modes sharing the frequency (relative tolerance 1e-6).
    system : LinearSystem
    """

    frequencies: np.ndarray
    shapes: np.ndarray
    eigenvalues: np.ndarray
    strain_energy: dict
    kinetic_energy: dict
    mode_type: list
    type_purity: np.ndarray
    harmonic: np.ndarray
    multiplicity: np.ndarray
    system: LinearSystem

    def dominant_spring(self, i: int) -> tuple[str, float]:
        """The spring holding most of mode i's strain energy, and its fraction."""
        name = max(self.strain_energy, key=lambda s: self.strain_energy[s][i])
        return name, float(self.strain_energy[name][i])

    def table(self) -> tuple[list, list]:
        """Rows and headers of a summary table (one row per mode)."""
        rows = []
        for i, f in enumerate(self.frequencies):
            name, frac = self.dominant_spring(i) if self.system.springs else ("-", 0.0)
            body = max(self.kinetic_energy, key=lambda b: self.kinetic_energy[b][i])
            rows.append([i + 1, f"{f:.2f}", self.mode_type[i], int(self.multiplicity[i]),
                         f"{self.type_purity[i]:.4f}", f"{name} ({100*frac:.0f} %)",
                         f"{body} ({100*self.kinetic_energy[body][i]:.0f} %)"])
        return rows, ["mode", "f (Hz)", "type", "multiplicity", "type purity", "max strain energy",
                      "max kinetic energy"]


def modes(system: LinearSystem, zero_tol: float = 1e-8) -> ModalResult:
    """Solve K phi = omega^2 M phi.

    Parameters
    ----------
    zero_tol : float
        Eigenvalues below ``zero_tol`` times the largest are rigid-body modes (0 Hz).
    """
    M, K = system.M, system.K
    if not np.all(np.isfinite(M)) or not np.all(np.isfinite(K)):
        raise ConfigError("linear system: non-finite mass or stiffness entries")
    w2, Phi = scipy.linalg.eigh(K, M)
    scale = max(abs(w2).max(), 1e-300)
    w2 = np.where(np.abs(w2) < zero_tol * scale, 0.0, w2)
    if np.any(w2 < 0):
        raise ConfigError(f"linear system is not positive semi-definite (eigenvalue {w2.min():.4g}): "
                          "a negative stiffness")
    freqs = np.sqrt(w2) / (2 * math.pi)
    # strain energy fractions per spring
    strain = {}
    tot = np.zeros(len(w2))
    for s in system.springs:
        e = 0.5 * s.k * (s.g @ Phi) ** 2
        strain[s.name] = strain.get(s.name, 0.0) + e
        tot += e
    if system.stiffness is not None:  # the springs split K only approximately: the rest is coupling
        full = 0.5 * _quadratic(Phi, K, Phi)
        strain[COUPLING] = full - tot
        tot = full
    elastic = w2 > 0  # rigid-body modes hold no strain energy
    strain = {k: np.where(elastic, v / np.where(elastic, tot, 1.0), 0.0) for k, v in strain.items()}
    kin = {}
    for name, (m, inertia, J) in system.bodies.items():
        u = J @ Phi
        kin[name] = 0.5 * (m * (u[0] ** 2 + u[1] ** 2) + inertia * u[2] ** 2)  # Phi M-normalised: sums to 1/2
    if system.mass is not None:  # modal coordinates: their inertia and frame coupling, per body
        dM = M - system.rigid_mass
        for name, rows in system.body_modes.items():
            rows = list(rows)
            cross = _quadratic(Phi[rows], dM[rows], Phi)
            own = _quadratic(Phi[rows], dM[np.ix_(rows, rows)], Phi[rows])
            kin[name] = kin.get(name, 0.0) + cross - 0.5 * own
    ksum = sum(kin.values())
    kin = {k: v / ksum for k, v in kin.items()}
    mult = _multiplicity(freqs)
    mtype, purity, harm = classify(system, Phi, M)
    return ModalResult(frequencies=freqs, shapes=Phi, eigenvalues=w2, strain_energy=strain, kinetic_energy=kin,
                       mode_type=mtype, type_purity=purity, harmonic=harm, multiplicity=mult, system=system)


def _quadratic(A: np.ndarray, M: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Column-wise a_m^T M b_m (``einsum("im,ij,jm->m")`` through a matrix product: the
    flexible systems with every gear mode a coordinate have hundreds of coordinates)."""
    return np.sum(A * (M @ B), axis=0)


def _multiplicity(freqs, rtol: float = 1e-6) -> np.ndarray:
    out = np.ones(len(freqs), int)
    i = 0
    while i < len(freqs):
        j = i + 1
        while j < len(freqs) and abs(freqs[j] - freqs[i]) <= rtol * max(freqs[i], 1e-9) + 1e-9:
            j += 1
        out[i:j] = j - i
        i = j
    return out


def harmonic_fractions(system: LinearSystem, Phi: np.ndarray, M: np.ndarray | None = None) -> np.ndarray | None:
    """Fraction of each mode's kinetic energy in each cyclic harmonic j = 0 .. N-1: (N, nmodes).

    The projector on harmonic j is (1/N) sum_k exp(-2 pi i j k / N) P^k, with P the symmetry
    operator; the projections are M-orthogonal because P commutes with M. None when the system
    has no cyclic symmetry (planets not equally spaced, or K, M not invariant under P)."""
    P = system.symmetry_operator()
    if P is None:
        return None
    M = system.M if M is None else M
    K = system.K
    tol = 1e-8
    if (np.abs(P @ M - M @ P).max() > tol * np.abs(M).max()
            or np.abs(P @ K - K @ P).max() > 1e-6 * np.abs(K).max()):
        return None
    N = len(system.planets)
    powers = [np.eye(system.n)]
    for _ in range(N - 1):
        powers.append(P @ powers[-1])
    norm = _quadratic(Phi, M, Phi)
    frac = np.zeros((N, Phi.shape[1]))
    for j in range(N):
        proj = sum(np.exp(-2j * math.pi * j * k / N) * powers[k] for k in range(N)) / N
        v = proj @ Phi
        frac[j] = np.real(_quadratic(v.conj(), M, v)) / norm
    return frac


def classify(system: LinearSystem, Phi: np.ndarray, M: np.ndarray | None = None):
    """Mode types (Lin & Parker), purity and dominant harmonic of each column of Phi."""
    nm = Phi.shape[1]
    frac = harmonic_fractions(system, Phi, M)
    if frac is None:
        return [UNCLASSIFIED] * nm, np.zeros(nm), np.full(nm, -1)
    N = frac.shape[0]
    translate = system.has_central_translation()
    groups = {ROTATIONAL: frac[0]}
    trans = frac[1] + (frac[N - 1] if N - 1 != 1 else 0.0)
    if translate:
        groups[TRANSLATIONAL] = trans
        groups[PLANET] = frac[2:N - 1].sum(axis=0) if N > 3 else np.zeros(nm)
    else:
        groups[PLANET] = frac[1:].sum(axis=0)
    names = list(groups)
    table = np.array([groups[k] for k in names])
    best = table.argmax(axis=0)
    return [names[b] for b in best], table.max(axis=0), frac.argmax(axis=0)


def expected_multiplicity(mode_type: str, N: int, central_translation: bool) -> int:
    """Lin & Parker's multiplicity of a mode type with N equally spaced planets."""
    if mode_type == ROTATIONAL:
        return 1
    if mode_type == TRANSLATIONAL:
        return 2
    return N - 3 if central_translation else N - 1


# =============================================================================================
# linearisation of the rigid model
# =============================================================================================


def pose_jacobians(model: Model, q: np.ndarray, angles: dict | None = None):
    """Poses (nb, 3) and pose Jacobians (nb, 3, n) of the bodies at coordinates q, mirroring the
    solver's kinematics. ``angles`` gives the angle of bodies whose rotation is not a coordinate
    (default: their ``theta0``)."""
    nb_ = len(model.bodies)
    n = len(q)
    pose = np.zeros((nb_, 3))
    J = np.zeros((nb_, 3, n))
    for i, (b, (ix, iy, ith)) in enumerate(zip(model.bodies, model.coordinate_indices())):
        if ith >= 0:
            pose[i, 2] = q[ith]
            J[i, 2, ith] = 1.0
        else:
            pose[i, 2] = (angles or {}).get(b.name, b.theta0)
        if ix >= 0:
            pose[i, 0], pose[i, 1] = q[ix], q[iy]
            J[i, 0, ix] = 1.0
            J[i, 1, iy] = 1.0
        else:
            pose[i, :2], J[i, :2] = _anchor(model, i, pose, J)
    return pose, J


def _anchor(model: Model, i: int, pose, J):
    """Position and Jacobian (2, n) of body i's anchor point (its pin on the parent or ground)."""
    b = model.bodies[i]
    par = b.parent
    if par < 0:
        return np.asarray(b.pin, float), np.zeros((2, J.shape[2]))
    c, s = math.cos(pose[par, 2]), math.sin(pose[par, 2])
    rx = c * b.pin[0] - s * b.pin[1]
    ry = s * b.pin[0] + c * b.pin[1]
    Ja = np.array([J[par, 0] - ry * J[par, 2], J[par, 1] + rx * J[par, 2]])
    return pose[par, :2] + np.array([rx, ry]), Ja


def _static_model(model: Model, drive: int, angle: float, torques: dict, free_drive_torque: float | None):
    """A copy of the model for statics: the driven body held at ``angle`` (or free with the torque
    ``free_drive_torque``), constant load torques, no ramps, no initial speeds."""
    bodies = []
    for i, b in enumerate(model.bodies):
        nb = dataclasses.replace(b, omega0=0.0, torque_ramp=0.0, attrs=dict(b.attrs))
        if i == drive:
            nb.theta0 = angle
            if free_drive_torque is None:
                nb.rotation = ANGLE_PRESCRIBED
                nb.speed = Profile.make(0.0)
            else:
                nb.rotation = ANGLE_FREE
                nb.speed = None
                nb.torque = Profile.make(free_drive_torque)
        elif b.torque is not None:
            nb.torque = Profile.make(torques[i])
        if b.torsion_parent == drive >= 0:  # a shaft to the driven body: its rest twist stays
            nb.theta0 = b.theta0 + angle - model.bodies[drive].theta0
        bodies.append(nb)
    out = copy.copy(model)
    out.bodies = bodies
    return out


def _kinematic_state(model: Model, drive: int, dth: float, ratio: np.ndarray) -> np.ndarray:
    """Coordinates of the unloaded (kinematic) configuration with the driven body turned by dth:
    every angle advanced by its speed ratio, centres on bearings at their anchor points (exact
    on the carrier's circle, not extrapolated along the tangent)."""
    names = model.coordinate_names()
    rate = {}
    for i, b in enumerate(model.bodies):
        nm = f"{b.name}.theta"
        rate[i] = 1.0 if i == drive else (ratio[names.index(nm)] if nm in names else 0.0)
    turned = copy.copy(model)
    turned.bodies = [dataclasses.replace(b, theta0=b.theta0 + rate[i] * dth) for i, b in enumerate(model.bodies)]
    q, _ = turned.initial_state()
    return q


def _equilibrium(model: Model, q0: np.ndarray, load_scale: float, tol: float = 1e-9, max_iter: int = 200):
    """Static equilibrium rhs(q) = 0 by Newton's method on the contact tangent, with a step limit
    (2 um), a small regularisation while contacts are open, and backtracking on the residual.

    The residual is scaled to forces (torques divided by the model's length scale) and compared
    with ``load_scale`` [N]."""
    q = q0.copy()
    v = np.zeros_like(q)
    names = model.coordinate_names()
    is_angle = np.array([n.endswith(".theta") for n in names])
    L = model.length_scale
    to_force = np.where(is_angle, 1.0 / L, 1.0)
    to_length = np.where(is_angle, L, 1.0)
    dmax = 2e-6  # m of motion per iteration

    def residual(x):
        ev_ = evaluate(model, x, v)
        return ev_, float(np.abs(ev_["rhs"] * to_force).max())

    ev, res = residual(q)
    best = (res, q, ev)
    stalled = 0
    for _ in range(max_iter):
        if res < tol * load_scale:
            return q, ev, res
        if res < best[0] * (1 - 1e-3):
            best, stalled = (res, q, ev), 0
        else:
            stalled += 1
        if stalled > 30:  # a contact appearing and vanishing between iterations (outline corner)
            break
        Kt = ev["Kt"]
        mu = 1e-6 * max(np.abs(np.diag(Kt) * to_force * to_force).max(), 1.0)
        A = Kt + mu * np.diag(1.0 / (to_force * to_force))
        dq = np.linalg.solve(A, ev["rhs"])
        move = np.abs(dq * to_length).max()
        if move > dmax:
            dq *= dmax / move
        lam = 1.0
        for _ in range(30):
            ev_t, res_t = residual(q + lam * dq)
            if res_t < res or move > dmax:  # limited steps move towards contact; accept them
                break
            lam *= 0.5
        q = q + lam * dq
        ev, res = ev_t, res_t
    if res < best[0]:
        best = (res, q, ev)
    return best[1], best[2], best[0]


def _mesh_contacts(ev, model: Model, m: int, J: np.ndarray, pose: np.ndarray):
    """Loaded contacts of mesh m: list of (k_c [N/m], g_c (n,), F_c [N], depth [m], nx, ny)."""
    mesh = model.meshes[m]
    a, b = mesh.a, mesh.b
    out = []
    for c in range(int(ev["count"][m])):
        F, depth, px, py, nx, ny = ev["cf"][m, c]
        if F <= 0.0 or depth <= 0.0:
            continue
        ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
        mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
        g = -(nx * J[a, 0] + ny * J[a, 1] + ma * J[a, 2]) + (nx * J[b, 0] + ny * J[b, 1] + mb * J[b, 2])
        k = mesh.K * mesh.e * depth ** (mesh.e - 1.0)
        out.append((k, g, F, depth, nx, ny))
    return out


def _cubic_step(x: float) -> float:
    """ADAMS STEP from 0 at x = 0 to 1 at x = 1 (cubic), clipped."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def _support_springs(model: Model, J: np.ndarray, pose: np.ndarray) -> list[Spring]:
    out = []
    for i, b in enumerate(model.bodies):
        if b.joint == BEARING:
            _, Ja = _anchor(model, i, pose, J)
            kind = "bearing" if b.parent >= 0 or b.attrs.get("role") in ("planet",) else "support"
            kind = "support" if b.attrs.get("role") == "ring" else kind
            label = f"{b.name} bearing"
            if b.attrs.get("shaft"):  # the shaft's bending with its bearings (flexgear.dynamics.model.shafts)
                kind, label = "shaft", f"{b.attrs['shaft']} shaft bending"
            out.append(Spring(f"{label} x", kind, b.stiffness, J[i, 0] - Ja[0]))
            out.append(Spring(f"{label} y", kind, b.stiffness, J[i, 1] - Ja[1]))
        if b.rotation == ANGLE_SPRING and b.torsion_parent >= 0:  # a shaft (flexgear.dynamics.model.shafts)
            p = b.torsion_parent
            shaft = b.attrs.get("shaft") or model.bodies[p].attrs.get("shaft", "")
            out.append(Spring(f"{shaft} shaft torsion".lstrip(), "shaft", b.torsional_stiffness, J[i, 2] - J[p, 2]))
        elif b.rotation == ANGLE_SPRING:
            out.append(Spring(f"{b.name} torsion", "support", b.torsional_stiffness, J[i, 2].copy()))
    return out


def _shaft_twist(model: Model, drive: int, torques: dict, ratio: np.ndarray) -> np.ndarray:
    """Coordinate change of the shafts' static twist (:mod:`flexgear.dynamics.model.shafts`), a start for the
    equilibrium: the input shaft (a spring to the driven motor body) transmits the torque of
    the power balance T_in w_gear + sum T_load w_load = 0 at the nominal speeds and turns the
    whole set behind it by -T_in / k; an output shaft turns its load body by T_load / k."""
    index = model.coordinate_indices()
    out = np.zeros(len(ratio))
    for i, b in enumerate(model.bodies):
        p, ith = b.torsion_parent, index[i][2]
        if b.rotation != ANGLE_SPRING or p < 0 or ith < 0 or b.torsional_stiffness <= 0:
            continue
        if p == drive and b.omega0 != 0.0:
            t_in = -sum(T * model.bodies[j].omega0 for j, T in torques.items()) / b.omega0
            out += ratio / ratio[ith] * (-t_in / b.torsional_stiffness)
        elif i in torques:
            out[ith] += torques[i] / b.torsional_stiffness
    return out


def _drive_and_loads(model: Model, load_time: float | None):
    drive = [i for i, b in enumerate(model.bodies) if b.speed is not None]
    if len(drive) != 1:
        raise ConfigError(f"linearisation needs exactly one driven body (prescribed speed), found {len(drive)}")
    torques = {}
    for i, b in enumerate(model.bodies):
        if b.torque is not None:
            t = load_time if load_time is not None else float(b.torque.t[-1]) + b.torque_ramp
            torques[i] = float(b.torque(t))
    if not torques or all(T == 0.0 for T in torques.values()):
        raise ConfigError("load.torque = 0: the linearisation point has no load (every tooth contact is "
                          "open, the mesh stiffness is zero); give a load torque > 0")
    return drive[0], torques


def _equilibria(model: Model, drive: int, torques: dict, n_positions: int, mesh_angle: float,
                approximate: list, skipped: list):
    """Static equilibria at ``n_positions`` drive angles over one mesh cycle (the drive held at
    each, the others free), each from the last one turned on kinematically. Yields ``(j, dth,
    sm, q, ev, q_kin)`` for the positions found: index, drive rotation [rad], the held model,
    its coordinates and evaluation, and the kinematic (rigid, unloaded) state; appends (j,
    residual) to ``approximate`` (accepted) or ``skipped`` (residual above
    :data:`APPROXIMATE_EQUILIBRIUM` of the load). Shared by both linearisations."""
    q0, ratio = _speed_ratio(model, drive)
    scale = _load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    twist = _shaft_twist(model, drive, torques, ratio)
    q_prev = None
    for j in range(n_positions):
        dth = mesh_angle * j / n_positions
        sm = _static_model(model, drive, theta_d0 + dth, torques, None)
        guess = (q0 + ratio * dth + twist) if q_prev is None else q_prev + ratio * (mesh_angle / n_positions)
        q, ev, res = _equilibrium(sm, guess, scale)
        if res > APPROXIMATE_EQUILIBRIUM * scale:
            skipped.append((j, res))
            q_prev = None
            continue
        if res >= 1e-9 * scale:
            approximate.append((j, res))
        q_prev = q
        yield j, dth, sm, q, ev, _kinematic_state(model, drive, dth, ratio)


def _speed_ratio(model: Model, drive: int):
    """The initial coordinates and each coordinate's speed per unit drive speed (kinematic)."""
    q0, v0 = model.initial_state()
    w0 = model.bodies[drive].omega0
    return q0, (v0 / w0 if w0 != 0 else np.zeros_like(v0))


def _load_scale(model: Model, torques: dict) -> float:
    """Largest applied torque over the model's length scale [N]: the equilibrium's force scale."""
    return max(abs(T) for T in torques.values()) / model.length_scale


def _valid_positions(skipped: list, found: bool, n_positions: int, scale: float) -> np.ndarray:
    """Mask of the positions with an equilibrium; an error if more than a quarter (or all) failed."""
    if len(skipped) > n_positions // 4 or not found:
        raise ConfigError(f"static equilibrium not found at {len(skipped)} of {n_positions} positions over a mesh "
                          f"cycle (largest residual {max(r for _, r in skipped):.3g} N for a load of {scale:.3g} N): "
                          "a tooth contact appears and vanishes there; check load.torque and the supports")
    bad = {i for i, _ in skipped}
    return np.array([j not in bad for j in range(n_positions)])


def _contact_lost(mesh, j: int, n_positions: int) -> ConfigError:
    return ConfigError(f"mesh '{mesh.name}' has no loaded tooth contact at the linearisation point "
                       f"(position {j} of {n_positions} over a mesh cycle): contact lost; increase load.torque")


def _roles(sm: Model, pose: np.ndarray) -> dict:
    """Planets, their angles [rad] and the central members of a held model, for LinearSystem."""
    planets = [i for i, b in enumerate(sm.bodies) if b.attrs.get("role") == "planet"]
    return {"planets": [sm.bodies[i].name for i in planets],
            "planet_angles": np.array([math.atan2(pose[i, 1], pose[i, 0]) for i in planets]),
            "central": [b.name for b in sm.bodies if b.attrs.get("role", "").split(",")[0] in ("sun", "carrier", "ring")]}


def modes_as_coordinates(model: Model) -> Model:
    """A copy of the flexible ``model`` with every condensed mode of its flexible bodies a modal
    coordinate (:mod:`flexgear.dynamics.flexible.floating_frame`), as with ``[flexible] dynamic_cutoff = cutoff``: the
    model whose linearisation is that of the condensed modes integrated in the contact solve
    (:mod:`flexgear.dynamics.flexible.condensed`: each mode's own inertia, its frame coupling S_i and its damping, exactly
    the equations of a modal coordinate).

    Condensed mode i of a body becomes a coordinate with unit modal mass, stiffness omega_i^2
    [1/s^2], damping 2 zeta omega_i [1/s], flank displacement A_i = ``shape`` x omega_i per unit
    coordinate [1/sqrt(kg)] and frame coupling S_i (zero where the interface is not the frame:
    a ring held on its rim or bolts, whose modes then carry no frame inertia, as when
    condensed); it follows the body's modal coordinates (ascending frequency). The residual
    tables (modes above the cutoff) stay. The model is returned unchanged when nothing is
    condensed.

    Raises
    ------
    ConfigError
        A body whose rigid mass or inertia is below what its modes carry (the mass matrix
        would be indefinite, :func:`~flexgear.dynamics.flexible.reductions.check_frame_inertia`).
    """
    if not any(fb.shape.shape[3] for fb in model.flex):
        return model
    bodies = [dataclasses.replace(b, attrs=dict(b.attrs)) for b in model.bodies]
    flex = []
    for fb in model.flex:
        nq = fb.shape.shape[3]
        if not nq:
            flex.append(fb)
            continue
        w = np.asarray(fb.condensed_omega, float)
        S = np.zeros((3, nq)) if fb.condensed_coupling is None else np.asarray(fb.condensed_coupling, float)
        damping = np.zeros(nq) if fb.condensed_damping is None else np.asarray(fb.condensed_damping, float)
        m0 = fb.modes

        def block(old, new):
            out = np.zeros((m0 + nq, m0 + nq))
            if m0:
                out[:m0, :m0] = old
            out[m0:, m0:] = new
            return out

        z, _, J, _ = fb.shape.shape
        shape = fb.shape * w  # A_i
        new = dataclasses.replace(
            fb, shape=np.zeros((z, 2, J, 0)),
            dynamic_shape=np.ascontiguousarray(shape if not m0 else np.concatenate([fb.dynamic_shape, shape], axis=3)),
            stiffness=block(fb.stiffness, np.diag(w * w)), mass=block(fb.mass, np.eye(nq)),
            damping=block(fb.damping, np.diag(damping)),
            frame_coupling=np.ascontiguousarray(S if not m0 else np.concatenate([fb.frame_coupling, S], axis=1)),
            frequencies=np.concatenate([fb.frequencies if m0 else np.zeros(0), w / (2 * math.pi)]),
            acceleration_shape=None if fb.acceleration_shape is None else np.zeros((z, 2, J, 3)),
            condensed_omega=np.zeros(0), condensed_damping=np.zeros(0), condensed_coupling=np.zeros((3, 0)),
            attrs=dict(fb.attrs, dynamic_modes=m0 + nq, condensed_modes=0))
        body = bodies[fb.body]
        body.attrs["mode_frequencies"] = [float(f) for f in new.frequencies]
        try:
            check_frame_inertia(body, new)
        except ConfigError as exc:
            raise ConfigError(f"linearisation with the condensed modes integrated (every mode a coordinate): {exc}; "
                              "or linearise with [flexible] condensation = 'static'") from exc
        flex.append(new)
    out = copy.copy(model)
    out.bodies, out.flex, out.attrs = bodies, flex, dict(model.attrs)
    return out


def linearise(model: Model, n_positions: int | None = None, free_drive: bool = False,
              load_time: float | None = None, condensation: str = "integrated") -> LinearSystem:
    """Linear system of the multi-body model about its loaded operating point (rigid: springs
    from the IMPACT tangent; flexible, :func:`is_flexible`: the solver's tangent, see the module
    docstring).

    Parameters
    ----------
    model : Model
        From :func:`flexgear.dynamics.model.assembly.build_model`.
    n_positions : int, optional
        Positions over one mesh cycle where the static equilibrium is solved and the mesh
        stiffness evaluated (default 8 N, or 24: a multiple of the planet count, so that every
        mesh sees the same phases).
    free_drive : bool
        False: the driven body's rotation is held (prescribed speed, as in the simulation).
        True: it is a free coordinate (reaction torque applied), so the set has a rigid-body
        rotation mode when nothing else holds it.
    load_time : float, optional
        Time [s] at which the load torque profiles are read (default: their last table time
        plus the ramp: the full load).
    condensation : {"integrated", "static"}
        How a flexible model's condensed modes enter, as in
        :func:`~flexgear.dynamics.integrator.simulation.simulate` (``[flexible] condensation``): integrated
        with their own inertia, i.e. each a modal coordinate (:func:`modes_as_coordinates`), or
        quasi-statically. No effect on a rigid model.

    Raises
    ------
    ConfigError
        ``condensation`` not one of the two, ``load.torque`` zero, no single driven body, a mesh without loaded contact at a
        position (contact lost), no static equilibrium at more than a quarter of the
        positions, or (flexible) a tangent stiffness that is not symmetric (forces not
        conservative at the operating point).
    """
    if condensation not in CONDENSATION:
        raise ConfigError(f"condensation = {condensation!r}: must be one of {', '.join(map(repr, sorted(CONDENSATION)))}")
    drive, torques = _drive_and_loads(model, load_time)
    f_in, f_m = model.attrs["input_frequency"], model.attrs["mesh_frequency"]
    N = sum(1 for b in model.bodies if b.attrs.get("role") == "planet")
    if n_positions is None:
        n_positions = 8 * N if N else 24
    if n_positions < 1:
        raise ConfigError(f"n_positions = {n_positions}: must be >= 1")
    mesh_angle = 2 * math.pi * f_in / f_m  # drive rotation over one mesh cycle [rad]
    if is_flexible(model):
        condensed = sum(fb.shape.shape[3] for fb in model.flex)
        if condensation == "integrated":
            model = modes_as_coordinates(model)
        out = _linearise_tangent(model, drive, torques, n_positions, free_drive, mesh_angle)
        out.attrs["condensation"] = condensation
        out.attrs["condensation_note"] = (
            "no condensed modes" if not condensed else
            f"the {condensed} condensed gear modes integrated with their own inertia (condensation = 'integrated'), "
            "linearised as modal coordinates" if condensation == "integrated" else
            f"the {condensed} condensed gear modes condensed quasi-statically (condensation = 'static')")
        return out
    scale = _load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    cycle = {key: np.zeros((len(model.meshes), n_positions)) for key in ("k", "force", "depth", "count", "damping",
                                                                       "deflection")}
    ref = None
    approximate, skipped = [], []
    for j, dth, sm, q, ev, q_kin in _equilibria(model, drive, torques, n_positions, mesh_angle, approximate,
                                                 skipped):
        pose, J = pose_jacobians(sm, q)
        for m, mesh in enumerate(model.meshes):
            cs = _mesh_contacts(ev, sm, m, J, pose)
            if not cs:
                raise _contact_lost(mesh, j, n_positions)
            cycle["k"][m, j] = sum(c[0] for c in cs)
            cycle["force"][m, j] = sum(c[2] for c in cs)
            cycle["depth"][m, j] = max(c[3] for c in cs)
            cycle["count"][m, j] = len(cs)
            g_j = sum(c[0] * c[1] for c in cs) / cycle["k"][m, j]
            cycle["deflection"][m, j] = g_j @ (q - q_kin)  # from the kinematic position
            cycle["damping"][m, j] = sum(mesh.C * _cubic_step(c[3] / mesh.d) for c in cs)
        if ref is None:
            ref = (q, ev, j)
    valid = _valid_positions(skipped, ref is not None, n_positions, scale)
    if not valid.all():  # fill skipped positions from their neighbours (periodic)
        x = np.arange(n_positions)
        for key, arr in cycle.items():
            for m in range(arr.shape[0]):
                arr[m, ~valid] = np.interp(x[~valid], x[valid], arr[m, valid], period=n_positions)
    k_mean = cycle["k"].mean(axis=1)
    q, ev, j_ref = ref
    theta_d0 = theta_d0 + mesh_angle * j_ref / n_positions
    reaction = -ev["Fb"][drive, 2]  # torque the drive must apply to hold the equilibrium
    if free_drive:
        sm = _static_model(model, drive, theta_d0, torques, reaction)
        names = sm.coordinate_names()
        old = dict(zip(_static_model(model, drive, theta_d0, torques, None).coordinate_names(), q))
        dn = f"{model.bodies[drive].name}.theta"
        q = np.array([old.get(nm, theta_d0) if nm != dn else theta_d0 for nm in names])
        ev = evaluate(sm, q, np.zeros_like(q))
    else:
        sm = _static_model(model, drive, theta_d0, torques, None)
    pose, J = pose_jacobians(sm, q)
    springs = _support_springs(sm, J, pose)
    mean_force, normals = {}, {}
    for m, mesh in enumerate(model.meshes):
        cs = _mesh_contacts(ev, sm, m, J, pose)
        kc = np.array([c[0] for c in cs])
        g = sum(c[0] * c[1] for c in cs) / kc.sum()
        springs.append(Spring(mesh.name, "mesh", float(k_mean[m]), g))
        mean_force[mesh.name] = float(sum(c[2] for c in cs))
        nrm = sum(c[0] * np.array([c[4], c[5]]) for c in cs)
        normals[mesh.name] = nrm / np.linalg.norm(nrm)
    bodies = {b.name: (b.mass, b.inertia, J[i]) for i, b in enumerate(sm.bodies)}
    out = LinearSystem(
        dofs=sm.coordinate_names(), bodies=bodies, springs=springs, **_roles(sm, pose),
        attrs={"source": "rigid model linearised about the loaded static equilibrium",
               "n_positions": n_positions, "mesh_stiffness": {m.name: float(k) for m, k in zip(model.meshes, k_mean)},
               "mesh_force": mean_force, "load_torques": {model.bodies[i].name: T for i, T in torques.items()},
               "drive_reaction_torque": float(reaction), "free_drive": free_drive, "q": q,
               "approximate_positions": approximate, "mesh_normal": normals, "cycle": cycle,
               "mesh_angle": mesh_angle, "drive": model.bodies[drive].name, "skipped_positions": skipped,
               "reference_position": j_ref})
    out.attrs["planet_asymmetry"] = symmetrise_planet_meshes(out)
    return out


# =============================================================================================
# linearisation of the flexible model: the solver's tangent
# =============================================================================================

#: Largest relative asymmetry of the solver's tangent stiffness that is symmetrised
#: (:func:`tangent_asymmetry`); beyond it the forces are not conservative at the operating
#: point and a modal analysis is refused. The flank tables' reciprocity (c_kl = c_lk) holds to
#: their interpolation, so the compliant tangent is symmetric to about 1e-5 in this measure.
TANGENT_ASYMMETRY = 1e-3


def tangent_asymmetry(K: np.ndarray) -> float:
    """max |K_ij - K_ji| / sqrt(|K_ii K_jj|) [-]: the asymmetry of a stiffness matrix relative
    to its diagonal, so that it does not depend on the coordinates' units (modal coordinates
    carry omega_i^2 up to 1.6e12 1/s^2 on the diagonal, contacts 1e8-1e9 N/m: relative to the
    largest entry an asymmetry of the contact terms would vanish)."""
    d = np.sqrt(np.abs(np.diag(K)))
    scale = np.maximum(np.outer(d, d), 1e-12 * max(float(d.max()) ** 2, 1e-300))
    return float((np.abs(K - K.T) / scale).max())


def is_flexible(model: Model) -> bool:
    """Whether the model has compliant meshes (:mod:`flexgear.dynamics.flexible.compliant`) or modal coordinates: it is
    linearised with the solver's tangent (:func:`_linearise_tangent`)."""
    return any(m.law == LAW_HERTZ for m in model.meshes) or bool(model.modal_coordinates())


def _contact_gradients(ev, model: Model, m: int, J: np.ndarray, pose: np.ndarray):
    """Loaded contacts of mesh m: list of (g_c (n,) rigid approach per unit coordinate, F_c [N],
    depth [m], flank side of body a (+1 / -1))."""
    mesh = model.meshes[m]
    a, b = mesh.a, mesh.b
    out = []
    for c in range(int(ev["count"][m])):
        F, depth, px, py, nx, ny = ev["cf"][m, c]
        if F <= 0.0:
            continue
        ma = (px - pose[a, 0]) * ny - (py - pose[a, 1]) * nx
        mb = (px - pose[b, 0]) * ny - (py - pose[b, 1]) * nx
        g = -(nx * J[a, 0] + ny * J[a, 1] + ma * J[a, 2]) + (nx * J[b, 0] + ny * J[b, 1] + mb * J[b, 2])
        out.append((g, float(F), float(depth), int(ev["ci"][m, c, 2])))
    return out


def _modal_springs(model: Model) -> tuple[list[Spring], dict]:
    """Springs omega_i^2 of the modal coordinates (unit modal mass) and each flexible body's
    modal coordinate indices. An off-diagonal modal stiffness stays in the coupling."""
    n = len(model.coordinate_names())
    springs, rows = [], {}
    for body, c0, m in model.modal_coordinates():
        fb = next(f for f in model.flex if f.body == body)
        name = model.bodies[body].name
        rows[name] = list(range(c0, c0 + m))
        for k in range(m):
            g = np.zeros(n)
            g[c0 + k] = 1.0
            springs.append(Spring(f"{name} mode {k + 1} ({fb.frequencies[k]:.0f} Hz)", "gear mode",
                                  float(fb.stiffness[k, k]), g))
    return springs, rows


def _mesh_decomposition(K_c: np.ndarray, G: np.ndarray, rigid: np.ndarray, to_length: np.ndarray):
    """Per-mesh springs of a contact tangent K_c (n, n) with mesh gradients G (nm, n; rigid
    coordinates only): K_c ~ H^T S H, H = [G_R, A].

    S (nm, nm) [N/m] is G'^+T K_c' G'^+ on the rigid coordinates in lengths (angles times the
    model's length scale, so the pseudo-inverse does not mix units): S_mm is mesh m's stiffness
    along its line of action with the other meshes' approaches held, S_mn (m != n) the contact
    coupling between meshes (through a flexible body's rim). A (nm, n_modal) is the modal part
    of each mesh's approach, from K_c[R, E] = G_R^T S A. Returns S, H (nm, n) and the relative
    Frobenius residual of the fit."""
    R = rigid
    E = ~rigid
    Gs = G[:, R] / to_length[R]
    Kr = K_c[np.ix_(R, R)] / np.outer(to_length[R], to_length[R])
    Gp = np.linalg.pinv(Gs)
    S = Gp.T @ Kr @ Gp
    S = 0.5 * (S + S.T)
    H = np.zeros_like(G)
    H[:, R] = G[:, R]
    if E.any():
        B = Gp.T @ (K_c[np.ix_(R, E)] / to_length[R][:, None])
        H[:, E] = np.linalg.lstsq(S, B, rcond=None)[0]
    fit = H.T @ S @ H
    res = np.linalg.norm(K_c - fit) / max(np.linalg.norm(K_c), 1e-300)
    return S, H, float(res)


#: Largest relative residual of :func:`modal_rotation` (flank fit and orthogonality of T).
ROTATION_RESIDUAL = 1e-3


def modal_rotation(fb: FlexBody, N: int) -> np.ndarray | None:
    """T (m, m), eta' = T eta: the modal coordinates of a flexible body's displacement field
    turned by 2 pi / N counter-clockwise (a central member of a set with N equally spaced
    planets), or None where it is not a symmetry of the modes.

    The body's z teeth are numbered counter-clockwise, so the turned field's normal flank
    displacement at tooth t is the field's at tooth t - z / N (the other sense would be a
    symmetry of the gear too, but not the planets' one: on MERCURY 1-A the cyclic mean would
    then move K and M by 68 %, against 4e-4): ``A T = A`` shifted by z / N
    teeth, solved in least squares over every flank sample A (z * 2 * J, m) of the modal
    coordinates. Kept when z is a multiple of N, the fit's residual and the departure of T
    from orthogonality (the modes are mass-orthonormal and the turn keeps the mass) are below
    :data:`ROTATION_RESIDUAL`: the kept modes must be closed under the turn (no degenerate pair
    split by the cutoff) and tell apart on the flanks. The fitted T is then made an exact
    turn of order N (orthogonal, T^N = I: its complex Schur form's eigenvalues set to the
    nearest N-th roots of unity), so the cyclic mean of the system is exactly invariant."""
    if not fb.modes or fb.dynamic_shape.shape[0] % N:
        return None
    z, m = fb.dynamic_shape.shape[0], fb.modes
    A = fb.dynamic_shape.reshape(-1, m)
    turned = np.roll(fb.dynamic_shape, z // N, axis=0).reshape(-1, m)
    T, *_ = np.linalg.lstsq(A, turned, rcond=None)
    fit = np.linalg.norm(A @ T - turned) / max(np.linalg.norm(turned), 1e-300)
    if not (fit <= ROTATION_RESIDUAL and np.abs(T.T @ T - np.eye(m)).max() <= ROTATION_RESIDUAL):
        return None
    U, _, Vt = np.linalg.svd(T)  # the nearest orthogonal matrix (a normal one: unitary Schur vectors)
    R, Z = scipy.linalg.schur(U @ Vt, output="complex")
    k = np.round(np.angle(np.diag(R)) * N / (2 * math.pi))
    exact = (Z * np.exp(2j * math.pi * k / N)) @ Z.conj().T
    if np.abs(exact - T).max() > 10 * ROTATION_RESIDUAL * max(np.abs(T).max(), 1.0):
        return None
    return np.ascontiguousarray(exact.real)


def _cyclic_mean(P: np.ndarray, A: np.ndarray, N: int) -> np.ndarray:
    """(1/N) sum_k P^k A P^-k: the part of A invariant under the planets' rotation (P orthogonal)."""
    out = np.zeros_like(A)
    Pk = np.eye(A.shape[0])
    for _ in range(N):
        out += Pk @ A @ Pk.T
        Pk = P @ Pk
    return out / N


def _linearise_tangent(model: Model, drive: int, torques: dict, n_positions: int, free_drive: bool,
                       mesh_angle: float) -> LinearSystem:
    """:func:`linearise` for a model with compliant meshes or modal coordinates.

    At each equilibrium position over a mesh cycle the solver's tangent stiffness Kt
    (:func:`~flexgear.dynamics.integrator.simulation.evaluate`: bearings, shafts, the joint tangent of all
    compliant contacts with their coupling across meshes, the modal stiffness omega_i^2 and the
    modes' share of each contact's approach) is taken, symmetrised and averaged over the cycle;
    the mass matrix is the solver's Mq at the reference position (the frame-mode coupling of
    the modal coordinates included) plus ``-dQ/dq''`` of the contact forces through the condensed
    modes' deflection under the frames' inertia load (symmetrised). For the energy table each mesh gets a spring along the
    line of action of its loaded drive-side contacts, of stiffness S_mm from
    :func:`_mesh_decomposition` (averaged over the cycle); the gears' modes get springs
    omega_i^2 on their coordinates; the rest of K (contact coupling between meshes, back-flank
    contacts off the line of action) is the :data:`COUPLING` entry."""
    _, ratio = _speed_ratio(model, drive)
    scale = _load_scale(model, torques)
    theta_d0 = model.bodies[drive].theta0
    nm = len(model.meshes)
    keys = ("k", "force", "depth", "count", "back_force", "deflection")
    cycle = {key: np.zeros((nm, n_positions)) for key in keys}
    coupling = np.zeros((nm, nm, n_positions))
    K_sum, S_sum, n_valid, asym_max, fit_max = None, None, 0, 0.0, 0.0
    approximate, skipped = [], []
    ref = None
    for j, dth, sm, q, ev, q_kin in _equilibria(model, drive, torques, n_positions, mesh_angle, approximate,
                                                 skipped):
        reaction = -ev["Fb"][drive, 2]  # torque the drive applies to hold the equilibrium
        held = {nme: i for i, nme in enumerate(sm.coordinate_names())}
        q_held = q
        if free_drive:  # the drive a coordinate, held by its reaction torque
            sm, q = _free_drive_state(model, drive, theta_d0 + dth, torques, sm, q, reaction)
            ev = evaluate(sm, q, np.zeros_like(q))
        Kt = ev["Kt"]
        asym = tangent_asymmetry(Kt)
        if asym > TANGENT_ASYMMETRY:
            raise ConfigError(f"the tangent stiffness at the operating point is not symmetric (relative asymmetry "
                              f"{asym:.3g} > {TANGENT_ASYMMETRY:g}): the forces are not conservative there, no modal "
                              "analysis")
        asym_max = max(asym_max, asym)
        K = 0.5 * (Kt + Kt.T)
        pose, J = pose_jacobians(sm, q)
        names = sm.coordinate_names()
        is_angle = np.array([nme.endswith(".theta") for nme in names])
        to_length = np.where(is_angle, model.length_scale, 1.0)
        rigid = np.arange(len(q)) < sm.rigid_coordinates()
        K_c = K - sum((s.k * np.outer(s.g, s.g) for s in _support_springs(sm, J, pose)), np.zeros_like(K))
        K_c -= sum((s.k * np.outer(s.g, s.g) for s in _modal_springs(sm)[0]), np.zeros_like(K))
        G = np.zeros((nm, len(q)))
        for m, mesh in enumerate(model.meshes):
            cs = _contact_gradients(ev, sm, m, J, pose)
            if not cs:
                raise _contact_lost(mesh, j, n_positions)
            by_side = {sd: sum(F for _, F, _, s_ in cs if s_ == sd) for sd in (1, -1)}
            side = max(by_side, key=by_side.get)
            drive_side = [c for c in cs if c[3] == side]
            G[m] = sum(F * g for g, F, _, _ in drive_side) / by_side[side]
            cycle["force"][m, j] = by_side[side] - by_side[-side]
            cycle["back_force"][m, j] = by_side[-side]
            cycle["depth"][m, j] = max(d for _, _, d, _ in cs)
            cycle["count"][m, j] = len(cs)
            cols = [names.index(nme) for nme in held]
            cycle["deflection"][m, j] = G[m, cols] @ (q_held - q_kin)  # rigid approach from the kinematic position
        S, H, fit = _mesh_decomposition(K_c, G, rigid, to_length)
        fit_max = max(fit_max, fit)
        cycle["k"][:, j] = np.diag(S)
        coupling[:, :, j] = S
        K_sum = K if K_sum is None else K_sum + K
        S_sum = _condensed_stiffness(K, rigid) if S_sum is None else S_sum + _condensed_stiffness(K, rigid)
        n_valid += 1
        if ref is None:
            ref = (j, sm, q, ev, H, reaction)
    valid = _valid_positions(skipped, ref is not None, n_positions, scale)
    k_mean = cycle["k"][:, valid].mean(axis=1)
    j_ref, sm, q, ev, H, reaction = ref
    K = K_sum / n_valid
    rigid = np.arange(len(q)) < sm.rigid_coordinates()
    if not rigid.all():
        # the modal coordinates' static condensation of the mean K is stiffer than the mean of
        # the condensed K (the Schur complement is concave in K: the contact moves along the
        # flanks and to the next tooth over the cycle, the mean spreads it). The rigid block is
        # corrected so that the quasi-static mesh stiffness is the cycle mean, as with static
        # condensation and in the rigid model (one position: no change)
        K[np.ix_(rigid, rigid)] += S_sum / n_valid - _condensed_stiffness(K, rigid)
    # the condensed modes' deflection under the frames' inertia load makes the contact forces
    # depend on the accelerations: -dQ/dq'' joins the mass (symmetrised: the Rayleigh quotient
    # of a mode is that of the unsymmetric term)
    M_inertia = evaluate(sm, q, np.zeros_like(q), acceleration_slope=1.0)["Kt"] - ev["Kt"]
    M = 0.5 * (ev["Mq"] + ev["Mq"].T + M_inertia + M_inertia.T)
    rigid_body_hz = 0.0
    if free_drive:
        # the kinematic rotation of the whole set (every angle at its speed ratio) is free: a
        # contact off the line of action (a tip corner) has moment arms off r_b1 : r_b2, which
        # resist it at one position and drive it at another; over a cycle they cancel. Project
        # it out of K (M-orthogonally); the frequency it had is kept in the attrs.
        names = sm.coordinate_names()
        held_ratio = dict(zip(model.coordinate_names(), ratio))
        r = np.array([1.0 if nme == f"{model.bodies[drive].name}.theta" else held_ratio.get(nme, 0.0)
                      for nme in names])
        Mr = M @ r
        rigid_body_hz = math.sqrt(max(r @ K @ r, 0.0) / (r @ Mr)) / (2 * math.pi)
        Q = np.eye(len(r)) - np.outer(r, Mr) / (r @ Mr)
        K = Q.T @ K @ Q
    pose, J = pose_jacobians(sm, q)
    modal, body_modes = _modal_springs(sm)
    springs = _support_springs(sm, J, pose) + modal
    for m, mesh in enumerate(model.meshes):
        springs.append(Spring(mesh.name, "mesh", float(k_mean[m]), H[m].copy()))
    bodies = {b.name: (b.mass, b.inertia, J[i]) for i, b in enumerate(sm.bodies)}
    roles = _roles(sm, pose)
    names = [mesh.name for mesh in model.meshes]
    out = LinearSystem(
        dofs=sm.coordinate_names(), bodies=bodies, springs=springs, **roles, stiffness=K, mass=M, body_modes=body_modes,
        attrs={"source": "flexible model linearised about the loaded static equilibrium (the solver's tangent "
                         "stiffness: compliant contacts solved jointly, modal coordinates)",
               "n_positions": n_positions, "mesh_stiffness": dict(zip(names, map(float, k_mean))),
               "mesh_coupling": {"meshes": names, "stiffness": coupling[:, :, valid].mean(axis=2)},
               "mesh_force": dict(zip(names, map(float, cycle["force"][:, valid].mean(axis=1)))),
               "load_torques": {model.bodies[i].name: T for i, T in torques.items()},
               "drive_reaction_torque": float(reaction),
               "free_drive": free_drive, "q": q, "approximate_positions": approximate, "cycle": cycle,
               "mesh_angle": mesh_angle, "drive": model.bodies[drive].name, "skipped_positions": skipped,
               "reference_position": j_ref, "tangent_asymmetry": asym_max, "mesh_fit_residual": fit_max,
               "rigid_body_frequency_removed": rigid_body_hz,
               "inertia_relief_mass": 0.5 * (M_inertia + M_inertia.T)})
    planets = set(roles["planets"])
    for fb in sm.flex:
        name = sm.bodies[fb.body].name
        if fb.modes and name not in planets and roles["planets"]:
            T = modal_rotation(fb, len(roles["planets"]))
            if T is not None:
                out.modal_rotation[name] = T
    asymmetry = symmetrise_planet_meshes(out)
    P = out.symmetry_operator()
    if P is not None:
        Np = len(roles["planets"])
        Ks, Ms = _cyclic_mean(P, K, Np), _cyclic_mean(P, M, Np)
        asymmetry = max(asymmetry, np.abs(Ks - K).max() / np.abs(K).max(), np.abs(Ms - M).max() / np.abs(M).max())
        out.stiffness, out.mass = Ks, Ms
    out.attrs["planet_asymmetry"] = float(asymmetry)
    return out


def _condensed_stiffness(K: np.ndarray, rigid: np.ndarray) -> np.ndarray:
    """Static condensation of the coordinates not in ``rigid`` (mask): K_rr - K_rm K_mm^-1 K_mr."""
    m = ~rigid
    if not m.any():
        return K[np.ix_(rigid, rigid)].copy()
    out = K[np.ix_(rigid, rigid)] - K[np.ix_(rigid, m)] @ np.linalg.solve(K[np.ix_(m, m)], K[np.ix_(m, rigid)])
    return 0.5 * (out + out.T)


def _free_drive_state(model: Model, drive: int, angle: float, torques: dict, held: Model, q: np.ndarray,
                      reaction: float):
    """The static model with the driven body free (held by the torque ``reaction``) and the
    coordinates q of the held model ``held`` extended by its angle."""
    sm = _static_model(model, drive, angle, torques, reaction)
    old = dict(zip(held.coordinate_names(), q))
    dn = f"{model.bodies[drive].name}.theta"
    return sm, np.array([angle if nm == dn else old[nm] for nm in sm.coordinate_names()])


def symmetrise_planet_meshes(system: LinearSystem) -> float:
    """Give the meshes of equally spaced planets their mean over the planets (in place).

    Each planet's meshes run through the same mesh cycle, shifted in phase, so their means over
    a cycle agree; the sampled positions and the direction taken at the reference position
    (tooth corners entering) differ slightly between planets. With P the rotation by 2 pi / N,
    mesh ``X-planet{n}`` gets g_n = (1/N) sum_k P^k g_(n-k) and the planets' mean stiffness,
    so the system is exactly cyclic symmetric (Lin & Parker's model). Returns the largest
    relative change of a stiffness or gradient (0 if not applicable)."""
    P = system.symmetry_operator()
    if P is None:
        return 0.0
    N = len(system.planets)
    groups = {}
    for idx, s in enumerate(system.springs):
        if s.kind != "mesh":
            continue
        for n, p in enumerate(system.planets):
            if p in s.name.replace("-", " ").split():
                groups.setdefault(s.name.replace(p, "#"), {})[n] = idx
    change = 0.0
    powers = [np.eye(system.n)]
    for _ in range(N - 1):
        powers.append(P @ powers[-1])
    for members in groups.values():
        if len(members) != N:
            continue
        k_mean = np.mean([system.springs[i].k for i in members.values()])
        new = {}
        for n, i in members.items():
            g = sum(powers[k] @ system.springs[members[(n - k) % N]].g for k in range(N)) / N
            old = system.springs[i]
            change = max(change, abs(old.k - k_mean) / k_mean,
                         np.abs(old.g - g).max() / max(np.abs(old.g).max(), 1e-300))
            new[i] = Spring(old.name, old.kind, float(k_mean), g)
        for i, sp in new.items():
            system.springs[i] = sp
    for sp in system.springs:
        if sp.kind == "mesh" and "mesh_stiffness" in system.attrs:
            system.attrs["mesh_stiffness"][sp.name] = sp.k
    return float(change)


def integrated_frequency(frequency, h: float, alpha: float):
    """Frequency [Hz] at which the solver's HHT-alpha integrator (:mod:`flexgear.dynamics.integrator.time_loop`, step h [s],
    alpha in [-1/3, 0], beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha) makes an undamped mode of
    natural frequency ``frequency`` [Hz] oscillate: arg(lambda) / (2 pi h) of the complex
    eigenvalue pair of the scheme's amplification matrix for x'' + omega^2 x = 0. The period
    grows with omega h (alpha = 0: exactly (2 / h) atan(omega h / 2)); at the rigid presets' 25 us
    step with alpha = -0.1 a 6.4 kHz mode runs at 5.82 kHz and an 8.9 kHz one at 7.60 kHz (at the
    flexible presets' 6.25 us: 8.79 kHz), so
    spectral peaks of simulations are matched to these values, not to the modes' own.
    Array input gives an array; 0 Hz stays 0."""
    if not (-1.0 / 3.0 - 1e-12 <= alpha <= 0.0) or not h > 0:
        raise ConfigError(f"integrated_frequency: h = {h!r} must be > 0 and alpha = {alpha!r} in [-1/3, 0]")
    beta, gamma = 0.25 * (1.0 - alpha) ** 2, 0.5 - alpha
    f = np.atleast_1d(np.asarray(frequency, float))
    out = np.zeros_like(f)
    for i, fi in enumerate(f):
        if fi <= 0:
            continue
        w2 = (2 * math.pi * fi) ** 2
        A = np.zeros((3, 3))
        for j, (x0, v0, a0) in enumerate(np.eye(3)):  # one step from each unit state (x, v, a)
            pred = x0 + h * v0 + h * h * (0.5 - beta) * a0
            a1 = (-(1 + alpha) * w2 * pred + alpha * w2 * x0) / (1 + (1 + alpha) * w2 * h * h * beta)
            A[:, j] = (pred + h * h * beta * a1, v0 + h * ((1 - gamma) * a0 + gamma * a1), a1)
        lam = np.linalg.eigvals(A)
        out[i] = abs(np.angle(lam[np.argmax(np.abs(lam.imag))])) / (2 * math.pi * h)
    return out if np.ndim(frequency) else float(out[0])


def modal_analysis(cfg, n_positions: int | None = None, free_drive: bool = False) -> ModalResult:
    """Modal analysis of a configuration's multi-body model (rigid, or flexible with a
    ``[flexible]`` block, its condensed modes as ``[flexible] condensation`` says) about its
    loaded operating point; with explicit lumped parameters (``[lumped.parameters]``), of the
    lumped model they define."""
    from ..model.assembly import build_model

    if cfg.model == "lumped" and (cfg.lumped or {}).get("parameters") is not None:
        from ..lumped.planetary import explicit_parameters, planetary_system

        return modes(planetary_system(explicit_parameters(cfg, free_drive=free_drive)))

    condensation = cfg.flexible["condensation"] if cfg.flexible else "integrated"
    return modes(linearise(build_model(cfg), n_positions=n_positions, free_drive=free_drive,
                           condensation=condensation))


MODAL_OUTPUTS = ("modes.md", "modes.json")


def report_markdown(result: ModalResult, title: str = "") -> str:
    """A Markdown report: modes table, mesh stiffnesses and the operating point."""
    def table(rows, headers):
        w = [max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(str(h)) for i, h in enumerate(headers)]
        out = ["| " + " | ".join(str(h).ljust(x) for h, x in zip(headers, w)) + " |",
               "|" + "|".join("-" * (x + 2) for x in w) + "|"]
        out += ["| " + " | ".join(str(c).ljust(x) for c, x in zip(r, w)) + " |" for r in rows]
        return "\n".join(out)

    sysl = result.system
    rows, headers = result.table()
    note = sysl.attrs.get("condensation_note")
    out = [f"# Modal analysis{': ' + title if title else ''}", "", sysl.attrs.get("source", ""), "",
           *([f"Condensed modes: {note}.", ""] if note else []),
           f"Coordinates: {', '.join(sysl.dofs)}", "", table(rows, headers), ""]
    ks = sysl.attrs.get("mesh_stiffness")
    if ks:
        fm = sysl.attrs.get("mesh_force", {})
        out += ["## Mesh stiffness at the operating point", "",
                table([[k, f"{v:.5g}", f"{fm.get(k, float('nan')):.5g}"] for k, v in ks.items()],
                      ["mesh", "mean tangent stiffness N/m", "normal force N"]), ""]
    cpl = sysl.attrs.get("mesh_coupling")
    if cpl is not None:
        names, S = cpl["meshes"], cpl["stiffness"]
        out += ["## Stiffness between meshes (flexible model)", "",
                "S[m, n] = force change of mesh m per unit approach of mesh n, the other meshes held [N/m] "
                "(diagonal: each mesh's own stiffness; off the diagonal: the contact coupling through the "
                "gears' rims), mean over the cycle.", "",
                table([[a] + [f"{v:.4g}" for v in row] for a, row in zip(names, S)], ["mesh"] + names), ""]
    if sysl.planets:
        N = len(sysl.planets)
        out += [f"Mode types for {N} equally spaced planets (Lin & Parker): rotational (multiplicity 1), "
                + ("translational (2), planet (N - 3)" if sysl.has_central_translation()
                   else "planet (N - 1; the central members have no translational coordinate)") + ".", ""]
    return "\n".join(out)


def write_modal_outputs(result: ModalResult, outdir, title: str = "", overwrite: bool = False) -> list:
    """Write ``modes.md`` (report) and ``modes.json`` (frequencies, shapes, energies) to outdir."""
    import json
    from pathlib import Path

    from ...files import atomic_write, check_targets

    outdir = Path(outdir)
    targets = [outdir / name for name in MODAL_OUTPUTS]
    check_targets(targets, overwrite)
    outdir.mkdir(parents=True, exist_ok=True)
    sysl = result.system
    data = {"title": title, "units": {"frequencies": "Hz", "shapes": "mass-normalised, per coordinate"},
            "dofs": sysl.dofs, "frequencies": result.frequencies.tolist(), "mode_type": result.mode_type,
            "multiplicity": result.multiplicity.tolist(), "type_purity": result.type_purity.tolist(),
            "shapes": result.shapes.T.tolist(),
            "strain_energy_fraction": {k: v.tolist() for k, v in result.strain_energy.items()},
            "kinetic_energy_fraction": {k: v.tolist() for k, v in result.kinetic_energy.items()},
            "mesh_stiffness": sysl.attrs.get("mesh_stiffness", {})}
    if sysl.attrs.get("condensation") is not None:
        data["condensation"] = {"mode": sysl.attrs["condensation"], "note": sysl.attrs["condensation_note"]}
    if sysl.attrs.get("mesh_coupling") is not None:
        data["mesh_coupling"] = {"meshes": sysl.attrs["mesh_coupling"]["meshes"],
                                 "stiffness": np.asarray(sysl.attrs["mesh_coupling"]["stiffness"]).tolist()}
    text = report_markdown(result, title)
    atomic_write(targets[0], lambda p: Path(p).write_text(text))
    atomic_write(targets[1], lambda p: Path(p).write_text(json.dumps(data, indent=1)))
    return targets
