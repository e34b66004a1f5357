"""Loaded mesh of a gear pair: load sharing between tooth pairs, static transmission error and mesh
stiffness from the FE influence coefficients and nonlinear Hertz contact (see
:mod:`flexgear.stiffness`, step 4).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..fe.meshing import USER_CACHE
from ..gears.material import Material
from .compliance import (DEFAULT_DEPTH, DEFAULT_POSITIONS, DEFAULT_SPREAD, HERTZ_MODES, ToothCompliance,
                         coupling_reach, tooth_compliance, tooth_step)
from .hertz import hertz_approach

# ============================================================================================
# loaded mesh of a pair
# ============================================================================================
#: Kinds of contact of a pair (:attr:`PairGrid.tip`): on the path of contact, tip corner of gear
#: 1 (after the path), tip corner of gear 2 (before the path).
ON_PATH, TIP1, TIP2 = 0, 1, 2
#: Largest no-load separation of a pair kept in the extended grid, in modules (0.1 m: several
#: times the loaded transmission error of steel gears).
MAX_GAP = 0.1
#: Most tooth pairs in contact at one mesh position that the extended grid may bring within reach
#: (it spans less than MAX_PAIRS base pitches; the pairs are up to MAX_PAIRS - 1 teeth apart).
MAX_PAIRS = 4


@dataclass
class PairGrid:
    """Contact positions along the line of action of a pair on a uniform grid.

        Attributes
        ----------
        s : ndarray (J,)
            Positions from the pitch point towards the tip of gear 1 [m], spacing p_b / n.
        n : int
            Grid points per base pitch.
        r1, r2, R : ndarray (J,)
            Contact radii on gear 1 and gear 2, relative radius of curvature [m].
        limits : tuple(float, float)
            Usable path [s_start, s_end] [m] (:func:`usable_path`).
        eps_alpha : float
            Contact ratio of the usable path, (s_end - s_start) / p_b [-].
        notes : list of str
            Why the path was shortened, if it was.
        gap, arm : ndarray (J,)
            No-load separation [m] and moment arm [-] of a pair at s (:class:`TipSeparation`).
        tip : ndarray (J,) of int
            ``ON_PATH``, ``TIP1`` (gear 1's tip corner, after the path) or ``TIP2`` (before it).
    """

    s: np.ndarray
    n: int
    r1: np.ndarray
    r2: np.ndarray
    R: np.ndarray
    limits: tuple
    eps_alpha: float
    notes: list
    gap: np.ndarray | None = None
    arm: np.ndarray | None = None
    tip: np.ndarray | None = None

    def __post_init__(self):
        J = len(self.s)
        self.gap = np.zeros(J) if self.gap is None else self.gap
        self.arm = np.ones(J) if self.arm is None else self.arm
        self.tip = np.full(J, ON_PATH) if self.tip is None else self.tip


def usable_path(pair) -> tuple[float, float, list]:
    """Path of contact on the involutes of both gears: (s_start, s_end, notes) [m].

        ISO 21771's path (-g_f, g_a) between the tip circles, ended at a mate's form circle where
        the tip would otherwise meet it below its involute (the interference the geometry check
        reports).
    """
    g1, g2 = pair.g1, pair.g2
    tw = math.tan(pair.alpha_w)
    gf, ga = pair.path_of_contact
    lo, hi, notes = -gf, ga, []
    t_form1 = math.sqrt(max(g1.r_form ** 2 - g1.rb ** 2, 0.0))
    s1 = t_form1 - g1.rb * tw  # gear 1 at its form circle
    if s1 > lo:
        notes.append(f"{g2.name} tip would contact {g1.name} below its form circle "
                     f"({g1.r_form*1e3:.4g} mm): path start moved by {(s1-lo)*1e3:.3g} mm")
        lo = s1
    t_form2 = math.sqrt(max(g2.r_form ** 2 - g2.rb ** 2, 0.0))
    s2 = (t_form2 - g2.rb * tw) if pair.internal else (g2.rb * tw - t_form2)
    if s2 < hi:
        notes.append(f"{g1.name} tip would contact {g2.name} beyond its form circle "
                     f"({g2.r_form*1e3:.4g} mm): path end moved by {(hi-s2)*1e3:.3g} mm")
        hi = s2
    return lo, hi, notes


def pair_grid(pair, n: int = DEFAULT_POSITIONS) -> PairGrid:
    """Uniform grid of contact positions over the usable path of contact of ``pair``."""
    g1, g2 = pair.g1, pair.g2
    lo, hi, notes = usable_path(pair)
    pb = g1.pb
    step = pb / n
    J = int(math.floor((hi - lo) / step + 1e-9)) + 1
    s = lo + step * np.arange(J)
    t1 = g1.rb * math.tan(pair.alpha_w) + s
    t2 = g2.rb * math.tan(pair.alpha_w) + (s if pair.internal else -s)
    r1, r2 = np.hypot(g1.rb, t1), np.hypot(g2.rb, t2)
    R = t1 * t2 / (t2 - t1) if pair.internal else t1 * t2 / (t1 + t2)
    return PairGrid(s=s, n=n, r1=r1, r2=r2, R=R, limits=(lo, hi), eps_alpha=(hi - lo) / pb,
                    notes=notes)


# ============================================================================================
# contact outside the path: tip corner against the mate's involute
# ============================================================================================
@dataclass
class TipSeparation:
    """Rigid no-load separation of a tooth pair at line-of-action positions s (:func:`tip_separation`).

        Attributes
        ----------
        s : ndarray (N,)
            Positions [m] (as :attr:`PairGrid.s`).
        gap : ndarray (N,)
            Transmission error (turn of gear 2 times r_b2, gear 1 held) at which the pair closes
            [m] (0 on the path).
        normal_gap : ndarray (N,)
            Distance of the tip corner from the mate's involute along its normal [m].
        arm : ndarray (N,)
            Moment arm of the contact normal about gear 2 over r_b2 [-] (~ normal_gap / gap).
        r1, r2 : ndarray (N,)
            Contact radii [m] (a corner: its tip radius; a flank: the foot of the normal).
        rho1, rho2 : ndarray (N,)
            Radii of curvature of the involutes at r1, r2 [m] (a corner: its own involute's at
            the tip, i.e. the corner is taken as rounded).
        R : ndarray (N,)
            Relative radius of curvature of the Hertz contact [m].
        tip : ndarray (N,) of int
            ``ON_PATH``, ``TIP1`` or ``TIP2``.
    """

    s: np.ndarray
    gap: np.ndarray
    normal_gap: np.ndarray
    arm: np.ndarray
    r1: np.ndarray
    r2: np.ndarray
    rho1: np.ndarray
    rho2: np.ndarray
    R: np.ndarray
    tip: np.ndarray


def _involute_constant(x, y, centre, rb):
    """c = phi + inv(alpha_r) of points (x, y) about ``centre`` for base radius rb: constant
    along every involute of that base circle unwound clockwise; two such involutes lie
    rb |c - c'| apart along their common normals (they are parallel curves)."""
    dx, dy = x - centre[0], y - centre[1]
    r = np.hypot(dx, dy)
    if np.any(r < rb * (1 - 1e-12)):
        raise ConfigError("tip_separation: a point lies inside a base circle (position too far "
                          "off the path of contact)")
    a = np.arccos(np.clip(rb / r, -1.0, 1.0))
    return np.arctan2(dy, dx) + np.tan(a) - a


def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def tip_separation(pair, s) -> TipSeparation:
    """Rigid no-load separation of a tooth pair whose involutes would touch at s.

        Gear 2 is at its conjugate position and turns against gear 1 (held); on the path the gap is
        0, before it gear 2's tip corner faces gear 1's involute, after it gear 1's corner faces gear
        2's. Closed form from the parallel involutes of one base circle: see the theory page
        *Lumped model*, section *FE mesh stiffness*.

        Parameters
        ----------
        pair : GearPair
        s : array_like
            Positions on the line of action from the pitch point, positive towards gear 1's tip [m].

        Returns
        -------
        TipSeparation
    """
    g1, g2 = pair.g1, pair.g2
    s = np.atleast_1d(np.asarray(s, float))
    aw, a = pair.alpha_w, pair.centre_distance
    rb1, rb2 = g1.rb, g2.rb
    sg = -1.0 if pair.internal else 1.0
    o1, o2 = (0.0, 0.0), (sg * a, 0.0)
    # contact point on the line of action: tangent point T1 + roll length along e
    t1 = rb1 * math.tan(aw) + s
    t2 = rb2 * math.tan(aw) + (s if pair.internal else -s)
    if np.any(t1 <= 0) or np.any(t2 <= 0):
        raise ConfigError(f"tip_separation: s beyond a base circle tangent point of pair {pair.name}")
    px = rb1 * math.cos(aw) + t1 * math.sin(aw)
    py = -rb1 * math.sin(aw) + t1 * math.cos(aw)
    lo, hi, _ = usable_path(pair)
    before, after = s < lo, s > hi
    gap = np.zeros_like(s)
    normal = np.zeros_like(s)
    arm = np.ones_like(s)
    r1, r2 = np.hypot(rb1, t1), np.hypot(rb2, t2)
    rho1, rho2 = t1.copy(), t2.copy()
    tip = np.full(s.shape, ON_PATH)
    if np.any(before):  # gear 2's tip corner against gear 1's involute
        c2 = _involute_constant(px[before], py[before], o2, rb2)
        a2 = math.acos(rb2 / g2.ra)
        c1_flank = _involute_constant(px[before], py[before], o1, rb1)

        def corner(turn):
            """Gear 2's corner turned by ``turn`` in its closing sense: position, normal distance
            from gear 1's flank, and the arm (-d distance / d turn) / r_b2."""
            phq = c2 - (math.tan(a2) - a2) + sg * turn
            qx, qy = o2[0] + g2.ra * np.cos(phq), o2[1] + g2.ra * np.sin(phq)
            g = rb1 * _wrap(_involute_constant(qx, qy, o1, rb1) - c1_flank)
            # normal of gear 1's involute at the corner: cos(alpha) e_phi + sin(alpha) e_r
            rq = np.hypot(qx, qy)
            aq = np.arccos(rb1 / rq)
            er = np.array([qx, qy]) / rq
            nrm = np.cos(aq) * np.array([-er[1], er[0]]) + np.sin(aq) * er
            # approach per unit turn of gear 2 in its closing sense: -sg n . (k x (Q - O2))
            lam = -sg * (nrm[0] * -(qy - o2[1]) + nrm[1] * (qx - o2[0])) / rb2
            return qx, qy, g, lam

        qx, qy, g, lam = corner(0.0)
        normal[before] = g
        # turn of gear 2 that closes the gap (Newton; the arm changes as the corner moves)
        turn = np.zeros_like(g)
        for _ in range(30):
            _, _, gt, lt = corner(turn)
            dt = gt / (lt * rb2)
            turn = turn + dt
            if np.all(np.abs(dt) * rb2 < 1e-13):
                break
        _, _, _, lam_c = corner(turn)
        arm[before], gap[before] = lam_c, turn * rb2
        rq = np.hypot(qx, qy)
        foot = np.sqrt(rq ** 2 - rb1 ** 2) - g  # roll length of the foot on gear 1's flank
        r1[before], rho1[before] = np.hypot(rb1, foot), foot
        r2[before], rho2[before] = g2.ra, math.sqrt(g2.ra ** 2 - rb2 ** 2)
        tip[before] = TIP2
    if np.any(after):  # gear 1's tip corner against gear 2's involute
        c1 = _involute_constant(px[after], py[after], o1, rb1)
        a1 = math.acos(rb1 / g1.ra)
        phq = c1 - (math.tan(a1) - a1)
        qx, qy = g1.ra * np.cos(phq), g1.ra * np.sin(phq)
        g = sg * rb2 * _wrap(_involute_constant(qx, qy, o2, rb2)
                             - _involute_constant(px[after], py[after], o2, rb2))
        normal[after], gap[after] = g, g  # normal tangent to gear 2's base circle: arm 1
        foot = np.sqrt((qx - o2[0]) ** 2 + (qy - o2[1]) ** 2 - rb2 ** 2) - sg * g
        r2[after], rho2[after] = np.hypot(rb2, foot), foot
        r1[after], rho1[after] = g1.ra, math.sqrt(g1.ra ** 2 - rb1 ** 2)
        tip[after] = TIP1
    R = rho1 * rho2 / (rho2 - rho1) if pair.internal else rho1 * rho2 / (rho1 + rho2)
    return TipSeparation(s=s, gap=gap, normal_gap=normal, arm=arm, r1=r1, r2=r2, rho1=rho1,
                         rho2=rho2, R=R, tip=tip)


def extended_grid(pair, n: int = DEFAULT_POSITIONS, max_gap: float = MAX_GAP,
                  max_pairs: int = MAX_PAIRS) -> PairGrid:
    """The grid of :func:`pair_grid` extended beyond the path to where a tip corner can touch under load.

        The uniform grid continues on each side whose path end is a tip circle while the no-load
        separation stays below ``max_gap``, the corner faces the mate's involute, the position stays
        between the base tangent points, and the grid spans less than ``max_pairs`` base pitches.
        :func:`loaded_mesh` raises if a pair at the last point of an extension is loaded.

        Parameters
        ----------
        pair : GearPair
        n : int
            Grid points per base pitch.
        max_gap : float
            Largest separation kept, in modules.
        max_pairs : int
            Most pairs at one position (>= 2).

        Returns
        -------
        PairGrid
            With ``gap``, ``arm`` and ``tip`` filled; ``limits`` and ``eps_alpha`` of the path.
    """
    if not (isinstance(max_gap, (int, float)) and max_gap > 0):
        raise ConfigError(f"max_gap = {max_gap!r}: must be a number > 0 (modules)")
    if isinstance(max_pairs, bool) or not isinstance(max_pairs, (int, np.integer)) or max_pairs < 2:
        raise ConfigError(f"max_pairs = {max_pairs!r}: must be an integer >= 2")
    base = pair_grid(pair, n)
    g1, g2 = pair.g1, pair.g2
    step = g1.pb / n
    J = len(base.s)
    room = max(max_pairs * n - J, 0)  # grid points that keep the span below max_pairs base pitches
    gf, ga = pair.path_of_contact
    lo, hi = base.limits
    notes = list(base.notes)
    cap = max_gap * g1.module
    lo2, hi2 = sorted((g2.r_form, g2.ra))

    def reach(sign, start, on_tip):
        if not on_tip:
            return 0
        k = 0
        while k < room:
            try:
                sep = tip_separation(pair, [start + sign * (k + 1) * step])
            except ConfigError:  # beyond a base circle's tangent point: no involute there
                break
            ok = (0.0 <= sep.gap[0] <= cap and g1.r_form - 1e-12 <= sep.r1[0] <= g1.ra + 1e-12
                  and lo2 - 1e-12 <= sep.r2[0] <= hi2 + 1e-12)
            if not ok:
                break
            k += 1
        return k

    tip_lo = math.isclose(lo, -gf, rel_tol=0, abs_tol=1e-12)
    tip_hi = math.isclose(hi, ga, rel_tol=0, abs_tol=1e-12)
    k_lo = reach(-1, base.s[0], tip_lo)
    k_hi = reach(+1, base.s[-1], tip_hi)
    if k_lo + k_hi > room:  # share the room between both ends
        k_lo = min(k_lo, max(room // 2, room - k_hi))
        k_hi = room - k_lo
    for side, k, on_tip in (("before", k_lo, tip_lo), ("after", k_hi, tip_hi)):
        if on_tip and k < 1:
            raise ConfigError(
                f"pair {pair.name}: no grid point {side} the path of contact within max_gap = "
                f"{max_gap:g} modules (separation one step out: "
                f"{tip_separation(pair, [(lo - step) if side == 'before' else (hi + step)]).gap[0]*1e6:.3g} um) "
                f"and {max_pairs} base pitches (room {room} points); raise max_gap, max_pairs or n")
        if not on_tip:
            notes.append(f"pair {pair.name}: no contact {side} the path (it ends at a form circle)")
    s = base.s[0] + step * np.arange(-k_lo, J + k_hi)
    sep = tip_separation(pair, s)
    if np.any(sep.gap < -1e-12):
        raise ConfigError(f"pair {pair.name}: rigid outlines overlap outside the path of contact "
                          f"(separation {sep.gap.min()*1e6:.3g} um)")
    return PairGrid(s=s, n=n, r1=sep.r1, r2=sep.r2, R=sep.R, limits=base.limits,
                    eps_alpha=base.eps_alpha, notes=notes, gap=sep.gap, arm=sep.arm, tip=sep.tip)


@dataclass
class MeshStiffness:
    """Quasi-static loaded mesh of a pair over one mesh cycle.

        Attributes
        ----------
        pair : GearPair
        grid : PairGrid
        load : float
            Total normal load F [N] (extended contact: torque on gear 2 over r_b2).
        s : ndarray (N,)
            Mesh position (first pair's contact position) over one base pitch [m].
        roll1 : ndarray (N,)
            Rotation of gear 1 from the first position, s / r_b1 [rad].
        n_pairs : ndarray (N,) int
            Pairs in contact.
        pair_loads : ndarray (N, P)
            Loads of the pairs at s, s + p_b, ... [N] (0 if open); P = max(3, most pairs at once).
        te : ndarray (N,)
            Static transmission error along the line of action [m].
        k_mesh : ndarray (N,)
            Mesh stiffness F / te [N/m].
        k_single : ndarray (J,)
            Single-pair stiffness over the grid (NaN outside the path) [N/m].
        c1, c2 : ToothCompliance
            FE data of the two gears.
        hertz : str
            Hertz formulation used.
    """

    pair: object
    grid: PairGrid
    load: float
    s: np.ndarray
    roll1: np.ndarray
    n_pairs: np.ndarray
    pair_loads: np.ndarray
    te: np.ndarray
    k_mesh: np.ndarray
    k_single: np.ndarray
    c1: ToothCompliance
    c2: ToothCompliance
    hertz: str

    @property
    def face_width(self) -> float:
        """Common face width b = min(b1, b2) [m]."""
        return self.pair.face_width

    @property
    def c_gamma(self) -> float:
        """Mean mesh stiffness per face width over one mesh cycle [N/m^2] (compare c_gamma_alpha)."""
        return float(np.mean(self.k_mesh)) / self.face_width

    @property
    def c_single(self) -> float:
        """Maximum single-pair stiffness per face width on the path [N/m^2] (compare ISO c')."""
        return float(np.nanmax(self.k_single)) / self.face_width

    @property
    def te_peak_to_peak(self) -> float:
        """Peak-to-peak static transmission error [m]."""
        return float(np.ptp(self.te))


def pair_compliance(tc1: ToothCompliance, tc2: ToothCompliance, idx, sig1: int, sig2: int):
    """Elastic compliance matrix (both gears, bulk) of the contacts at grid indices ``idx``
    (consecutive pairs one base pitch apart, idx[k] = idx[0] + k n): contacts a and b lie
    |a - b| teeth apart on each gear and couple through the table of that tooth distance."""
    n = len(idx)
    C = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            if a == b:
                C[a, a] = tc1.bulk[idx[a]] + tc2.bulk[idx[a]]
                continue
            for tc, sig in ((tc1, sig1), (tc2, sig2)):
                d = sig * (a - b)  # tooth of contact a relative to the loaded tooth (contact b)
                if d not in tc.coupling:
                    raise ConfigError(
                        f"{tc.gear.name}: contacts {abs(d)} teeth apart need the coupling at tooth "
                        f"distance {abs(d)}; the compliance tables reach {tc.reach} "
                        f"(tooth_compliance(..., neighbours={abs(d)}))")
                C[a, b] += tc.coupling[d][idx[a], idx[b]]
    return C


def share_load(C, hertz_fn, F: float, tol: float = 1e-10, max_iter: int = 100, gap=None, arm=None):
    """Load sharing between the pairs of one mesh position (secant iteration, active set): solves
    ``arm_k (delta - gap_k) = sum_l C_kl F_l + h_k(F_k)``, ``sum_k arm_k F_k = F`` for the loaded
    pairs, F_k = 0 for the open ones (gap = 0, arm = 1: the path only). Returns (F_k [N], delta [m])."""
    n = C.shape[0]
    gap = np.zeros(n) if gap is None else np.asarray(gap, float)
    arm = np.ones(n) if arm is None else np.asarray(arm, float)
    active = np.ones(n, bool)
    Fk = np.full(n, F / n)
    for _ in range(2 * n + 2):
        idx = np.flatnonzero(active)
        f = Fk[idx].copy()
        f[f <= 0] = F / len(idx)
        for _it in range(max_iter):
            h = np.array([hertz_fn(i, fi) / fi for i, fi in zip(idx, f)])
            A = np.zeros((len(idx) + 1, len(idx) + 1))
            A[:-1, :-1] = C[np.ix_(idx, idx)] + np.diag(h)
            A[:-1, -1] = -arm[idx]
            A[-1, :-1] = arm[idx]
            rhs = np.zeros(len(idx) + 1)
            rhs[:-1] = -arm[idx] * gap[idx]
            rhs[-1] = F
            sol = np.linalg.solve(A, rhs)
            fnew, delta = sol[:-1], sol[-1]
            if np.any(fnew <= 0):
                break
            done = np.max(np.abs(fnew - f)) < tol * F
            f = fnew
            if done:
                break
        if np.all(fnew > 0):
            Fk = np.zeros(n)
            Fk[idx] = fnew
            # an open pair that the transmission error closes joins
            free = arm * (delta - gap) - C @ Fk
            closing = (~active) & (free > 0)
            if not np.any(closing):
                return Fk, float(delta)
            active |= closing
            continue
        worst = idx[np.argmin(fnew)]
        active[worst] = False
        Fk = np.zeros(n)
        Fk[idx] = np.maximum(fnew, 0)
    raise RuntimeError("load sharing did not converge")


def loaded_mesh(pair, load: float, *, settings=None, material: Material | None = None,
                formulation: str = "plane_stress", hertz: str = "plane_strain",
                n_positions: int = DEFAULT_POSITIONS, spread: float = DEFAULT_SPREAD,
                depth: float = DEFAULT_DEPTH, cache_dir=USER_CACHE, models=None,
                extended: bool = False, max_gap: float = MAX_GAP, max_pairs: int = MAX_PAIRS,
                compliances=None) -> MeshStiffness:
    """Static transmission error and mesh stiffness of a pair over one mesh cycle.

        Compatibility and equilibrium of the loaded pairs with FE tooth compliances and nonlinear
        Hertz contact; see the theory page *Lumped model*, section *FE mesh stiffness*. With
        ``extended=True`` pairs also carry load outside the path, where a tip corner meets the
        mate's involute (gear 1 held, gear 2 turned by the torque F r_b2); the default is the path
        only, as ISO 6336 assumes.

        Parameters
        ----------
        pair : GearPair
            g1 external, g2 external or internal; both gears meshed and clamped (hub / rim).
        load : float
            Total normal tooth force along the line of action F [N]; with ``extended``, the torque
            on gear 2 over r_b2.
        settings : MeshSettings, optional
        material : Material, optional
            Both gears (steel defaults).
        formulation : {"plane_stress", "plane_strain"}
            FE formulation of the bodies.
        hertz : {"plane_strain", "plane_stress", "same"}
            Formulation of the Hertz near field ("same": as the FE).
        n_positions : int
            Mesh positions per base pitch.
        spread, depth : float
            Patch half-width and reference depth, in modules.
        cache_dir : path or None
            Mesh cache directory (default the per-user cache; None: no cache).
        models : tuple(FEModel, FEModel), optional
            Pre-assembled models of g1 and g2.
        extended : bool
            Contact outside the path of contact.
        max_gap, max_pairs : float, int
            As in :func:`extended_grid`.
        compliances : tuple(ToothCompliance, ToothCompliance), optional
            ``.c1``, ``.c2`` of an earlier result on the same grid and settings: they do not depend
            on the load, so a load sweep computes them once.

        Returns
        -------
        MeshStiffness
            With ``extended``, ``s`` starts at the extended grid's first point and ``k_single`` is
            NaN outside the path.
    """
    if not load > 0:
        raise ConfigError(f"load = {load!r}: must be > 0 N")
    if hertz not in HERTZ_MODES:
        raise ConfigError(f"hertz = {hertz!r}: must be one of {HERTZ_MODES}")
    material = Material() if material is None else material
    g1, g2 = pair.g1, pair.g2
    grid = (extended_grid(pair, n_positions, max_gap, max_pairs) if extended
            else pair_grid(pair, n_positions))
    n, J = grid.n, len(grid.s)
    most = -(-J // n)  # most pairs at one position: ceil(J / n)
    if most > max_pairs:
        raise ConfigError(f"pair {pair.name}: up to {most} tooth pairs in contact at once on its grid "
                          f"(contact ratio {grid.eps_alpha:.4g} on the path); at most max_pairs = "
                          f"{max_pairs} are supported")
    reach = max(most - 1, 1)  # tooth distances coupled (at least the neighbours, as before)
    for g in (g1, g2):
        coupling_reach(g, reach)  # a clear error if a gear has too few teeth for that reach
    m1, m2 = (None, None) if models is None else models
    if compliances is not None:
        tc1, tc2 = compliances
        if len(tc1.bulk) != len(grid.s) or len(tc2.bulk) != len(grid.s):
            raise ConfigError(f"compliances: computed on {len(tc1.bulk)} / {len(tc2.bulk)} contact positions, "
                              f"the grid of pair {pair.name} with n_positions = {n_positions} has {len(grid.s)}")
        if min(tc1.reach, tc2.reach) < most - 1:
            raise ConfigError(f"compliances: coupling tables reach {tc1.reach} / {tc2.reach} teeth, pair "
                              f"{pair.name} has up to {most} pairs in contact ({most - 1} teeth apart)")
    else:
        tc1 = tooth_compliance(g1, grid.r1, settings=settings, material=material,
                               formulation=formulation, spread=spread, depth=depth,
                               neighbours=reach, cache_dir=cache_dir, model=m1)
        tc2 = tooth_compliance(g2, grid.r2, settings=settings, material=material,
                               formulation=formulation, spread=spread, depth=depth,
                               neighbours=reach, cache_dir=cache_dir, model=m2)
    hform = formulation if hertz == "same" else hertz
    L = min(g1.face_width, g2.face_width)

    def hertz_fn(j, F):
        return hertz_approach(F, grid.R[j], L, material, material, tc1.depth, tc2.depth, hform)

    # tooth index step per +p_b along s: gear 1 radius grows with s; external gear 2 shrinks,
    # internal gear 2 grows
    sig1 = tooth_step(g1)
    sig2 = tooth_step(g2) * (1 if pair.internal else -1)
    k_single = np.array([load / ((tc1.bulk[j] + tc2.bulk[j]) * load + hertz_fn(j, load))
                         if grid.tip[j] == ON_PATH else np.nan for j in range(J)])
    npos = min(n, J)
    te = np.zeros(npos)
    loads = np.zeros((npos, max(3, most)))
    npairs = np.zeros(npos, int)
    ends = {0, J - 1} if extended else set()
    for k in range(npos):
        idx = list(range(k, J, n))
        C = pair_compliance(tc1, tc2, idx, sig1, sig2)
        Fk, delta = share_load(C, lambda i, F: hertz_fn(idx[i], F), load, gap=grid.gap[idx],
                           arm=grid.arm[idx])
        for i, j in enumerate(idx):
            if j in ends and Fk[i] > 0 and grid.tip[j] != ON_PATH:
                raise ConfigError(
                    f"pair {pair.name}, load {load:.4g} N: a pair outside the path carries load at "
                    f"the end of the extended grid (s = {grid.s[j]*1e3:.4g} mm; the grid ends at "
                    f"max_gap = {max_gap:g} modules, at max_pairs = {max_pairs} base pitches, where "
                    f"the corner leaves the mate's involute or at a base circle's tangent point): raise "
                    f"max_gap or max_pairs if they ended it, else the load is beyond this analysis")
        te[k] = delta
        loads[k, :len(idx)] = Fk
        npairs[k] = int(np.count_nonzero(Fk > 0))
    s = grid.s[:npos]
    return MeshStiffness(pair=pair, grid=grid, load=load, s=s, roll1=(s - s[0]) / g1.rb,
                         n_pairs=npairs, pair_loads=loads, te=te, k_mesh=load / te,
                         k_single=k_single, c1=tc1, c2=tc2, hertz=hertz)




def impact_sharing(load: float, K: float, e: float, gaps) -> tuple[np.ndarray, float]:
    """Quasi-static load sharing of the tooth pairs of one mesh position in the rigid multi-body
    model: :func:`loaded_mesh`'s compatibility and equilibrium of the loaded pairs with each pair
    the IMPACT law F = K delta^e [N/m^e] of the rigid model (no elastic coupling between pairs,
    the pairs on the path: moment arm 1).

    Parameters
    ----------
    load : float
        Total normal load F [N] along the line of action.
    K, e : float
        IMPACT stiffness [N/m^e] and exponent.
    gaps : array_like (n,)
        No-load separation of each pair [m] at its contact position: 0 for healthy involutes,
        the material a modified outline removes there (profile relief, a spall's depth; ``inf``
        for a missing tooth).

    Returns
    -------
    loads : ndarray (n,)
        Pair loads [N] (0: open).
    delta : float
        Loaded transmission error along the line of action [m].
    """
    gaps = np.asarray(gaps, float)
    if not np.any(np.isfinite(gaps)):
        raise ConfigError("impact_sharing: no pair can carry the load (every gap infinite)")
    live = np.isfinite(gaps)
    loads = np.zeros(len(gaps))
    C = np.zeros((live.sum(), live.sum()))
    f, delta = share_load(C, lambda i, F: (F / K) ** (1.0 / e), float(load), gap=gaps[live])
    loads[live] = f
    return loads, delta
