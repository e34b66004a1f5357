"""Linear systems and their modes: a mass matrix and springs (or explicit K and M), natural frequencies, mass-normalised mode shapes, modal energies and mode types.

A spring (gear mesh, bearing, support) has a stiffness k and a gradient g (deflection g . q),
so K = sum_s k_s g_s g_s^T; M = sum_b J_b^T diag(m_b, m_b, I_b) J_b over the bodies' pose
Jacobians. Mode types of equally spaced planets (rotational, translational, planet; Lin &
Parker 1999) are computed from the mode's energy in each cyclic harmonic. See the theory page
*Linearisation and modal analysis*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ...errors import ConfigError
from ..model.bodies import FlexBody

ROTATIONAL, TRANSLATIONAL, PLANET, UNCLASSIFIED = "rotational", "translational", "planet", "-"
#: Strain-energy entry of an explicit stiffness matrix not represented by the springs.
COUPLING = "coupling (K - springs)"


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
            Explicit K (flexible model: the solver's tangent); the springs then only split a mode's
            strain energy, the rest being :data:`COUPLING`. None: K = sum k g g^T.
        mass : ndarray (n, n), optional
            Explicit M (flexible model: the solver's Mq). None: M = sum J^T diag(m, m, I) J.
        body_modes : dict name -> list of int
            Indices of each flexible body's modal coordinates.
        modal_rotation : dict name -> ndarray (m, m)
            For a central member with modal coordinates: T with eta' = T eta its displacement field
            turned by 2 pi / N (:func:`modal_rotation`); without it the system has no symmetry
            operator.
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

    def multiplicity_note(self, i: int) -> str:
        """Mode i's multiplicity as table text: the number, and ``accidental`` where the modes at
        its frequency are of different types, or more of one type than Lin & Parker's
        (:func:`expected_multiplicity`): a coincidence of the parameters, not the symmetry."""
        m = int(self.multiplicity[i])
        t = self.mode_type[i]
        if t == UNCLASSIFIED or m == 1:
            return str(m)
        group = [j for j in range(len(self.frequencies)) if self.multiplicity[j] == m
                 and abs(self.frequencies[j] - self.frequencies[i]) <= 1e-6 * max(self.frequencies[i], 1e-9) + 1e-9]
        types = sorted({self.mode_type[j] for j in group})
        expected = expected_multiplicity(t, len(self.system.planets), self.system.has_central_translation())
        if len(types) > 1:
            return f"{m} (accidental: {' + '.join(f'{sum(self.mode_type[j] == u for j in group)} {u}' for u in types)})"
        return str(m) if m == expected else f"{m} (accidental: {t} modes come in {expected})"

    def table(self) -> tuple[list, list]:
        """Rows and headers of a summary table (one row per mode). Type purity is ``n/a`` where
        mode types do not apply (no cyclic symmetry: a spur pair, unequally spaced planets)."""
        rows = []
        for i, f in enumerate(self.frequencies):
            name, frac = self.dominant_spring(i) if self.system.springs else ("-", 0.0)
            body = max(self.kinetic_energy, key=lambda b: self.kinetic_energy[b][i])
            purity = "n/a" if self.mode_type[i] == UNCLASSIFIED else f"{self.type_purity[i]:.4f}"
            strain = f"{name} ({100*frac:.0f} %)" if frac > 0.0 else "- (none: a rigid-body mode)"
            rows.append([i + 1, f"{f:.2f}", self.mode_type[i], self.multiplicity_note(i), purity, strain,
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
