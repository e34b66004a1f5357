"""Contact-point data of a reduced gear: modal flank displacements and residual compliance tables.

Clamped modes miss the tooth's local deflection under a contact force; the residual
flexibility (:mod:`flexgear.reduction.residual`) carries it, tabulated here at the contact
points rather than as attachment modes (one stiff coordinate per flank point). The tables run
from the flank points of the teeth of one support period to both flanks of every tooth (modes
alone misstate the coupling of teeth far apart) and serve every tooth by cyclic symmetry.
Points and measure are those of :mod:`flexgear.stiffness.compliance` (unit-resultant biweight
patch, patch-weighted mean normal displacement, symmetric tables); the self term has the
half-plane near field removed, which the Hertz law carries. The solver reads, per tooth k,
side s, radius r and force F along the flank normal into the tooth::

    Q = F A_k,s(r)
    delta = A_k,s(r) . q + c_self,s(r) F + sum_l c_res(k, s, r; l, s_l, r_l) F_l

(``A`` includes the three frame coordinates). See the theory page *Reduction and residual
tables*, section *Flank tables*.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..fe.loads import flank_patch_load
from ..stiffness.compliance import DEFAULT_DEPTH, DEFAULT_SPREAD, MIN_SPREAD
from ..stiffness.hertz import halfplane_compliance

SIDES = (1, -1)
#: Default number of table radii per flank (self compliance and mode shapes): with linear
#: interpolation the spur pair's mesh lines converge to about 0.3 % at 129 radii
#: (``tests/test_table_convergence.py``).
DEFAULT_TABLE_POINTS = 129
#: Default number of radii of the tables between different flank points (a subset of the table
#: radii, every ``(table points - 1) / (coupling points - 1)``-th): those fields are smooth in
#: both radii (tooth bending and rim), and 17 radii change the spur pair's lines by < 1 %
#: against 129 while keeping the z x 4 tables of every tooth distance small.
DEFAULT_COUPLING_POINTS = 17


def flank_group(gear, tooth: int, side: int) -> str:
    """Boundary group of a flank: side +1 = ``tooth{k}_left``, -1 = ``tooth{k}_right``."""
    if side not in SIDES:
        raise ConfigError(f"side = {side!r}: must be +1 (left flank) or -1 (right flank)")
    return f"tooth{tooth % gear.z}_{'left' if side > 0 else 'right'}"


def flank_arc_range(model, gear, side: int = 1, tooth: int = 0) -> tuple[float, float]:
    """Involute arc-length range [S_lo, S_hi] [m] of the meshed flank of ``tooth`` (a healthy one:
    every healthy tooth has the same)."""
    name = flank_group(gear, tooth, side)
    if name not in model.mesh.boundaries:
        raise ConfigError(f"mesh of {gear.name} has no boundary {name!r}")
    nodes = np.unique(model.mesh.facets[:, model.mesh.boundaries[name]])
    r = np.hypot(*model.mesh.p[:, nodes])
    S = (r * r - gear.rb ** 2) / (2.0 * gear.rb)
    return float(S.min()), float(S.max())


def flank_patch_loads(model, gear, tooth: int, side: int, radii, spread: float = DEFAULT_SPREAD,
                      min_spread: float = MIN_SPREAD):
    """Unit-resultant patch loads on one flank at contact radii.

    Parameters
    ----------
    model : FEModel
    gear : SpurGear
    tooth : int
        Tooth index (mesh groups ``tooth{k}_left/right``; taken modulo z).
    side : {+1, -1}
        Left or right flank.
    radii : array_like
        Contact radii [m] on the meshed involute.
    spread, min_spread : float
        Patch half-width and its smallest value where it meets the flank's end [modules].

    Returns
    -------
    F : ndarray (ndofs, J)
        Load vectors [N per N].
    widths : ndarray (J,)
        Half-widths used [m].
    lo, hi : ndarray (J,)
        Support clipped at the flank ends, in units of the width.
    """
    flank = flank_basis(model, gear, tooth, side)
    cols, widths, los, his = [], [], [], []
    for r in np.atleast_1d(np.asarray(radii, float)):
        f, w, lo, hi = flank_patch(model, gear, flank, r, spread, min_spread)
        cols.append(f)
        widths.append(w)
        los.append(lo)
        his.append(hi)
    return np.column_stack(cols), np.array(widths), np.array(los), np.array(his)


def flank_basis(model, gear, tooth: int, side: int):
    """Facet basis of one flank (mesh group ``tooth{k}_left/right``) and the flank's arc range
    ``(S_lo, S_hi)`` [m]: what :func:`flank_patch` needs, built once per flank."""
    from skfem import FacetBasis

    name = flank_group(gear, tooth, side)
    if name not in model.mesh.boundaries:
        raise ConfigError(f"mesh of {gear.name} has no boundary {name!r}")
    fb = FacetBasis(model.mesh, model.basis.elem, facets=model.mesh.boundaries[name], intorder=8)
    return fb, flank_arc_range(model, gear, side)


def flank_patch(model, gear, flank, r: float, spread: float = DEFAULT_SPREAD, min_spread: float = MIN_SPREAD):
    """Unit-resultant patch load at contact radius r on a flank from :func:`flank_basis`.

    Returns
    -------
    f : ndarray (ndofs,)
        Load vector [N per N].
    w : float
        Half-width [m] (``spread`` modules, narrowed to ``min_spread`` where the flank ends).
    lo, hi : float
        Support clipped at the flank ends, in units of the width.
    """
    fb, (S_lo, S_hi) = flank
    m, rb = gear.module, gear.rb
    Sc = (r * r - rb * rb) / (2.0 * rb)
    if not (S_lo - 1e-9 <= Sc <= S_hi + 1e-9):
        raise ConfigError(
            f"{gear.name}: contact radius {r*1e3:.6g} mm lies off the meshed flank (arc "
            f"{Sc*1e3:.4g} mm not in [{S_lo*1e3:.4g}, {S_hi*1e3:.4g}] mm)")
    w = min(spread * m, max(min_spread * m, min(Sc - S_lo, S_hi - Sc)))
    f = flank_patch_load(fb, rb, Sc, w, model.thickness, 2, f"{gear.name}: patch at r = {r*1e3:.6g} mm")
    return f, w, max(-1.0, (S_lo - Sc) / w), min(1.0, (S_hi - Sc) / w)


def modal_shapes(body, gear, tooth: int, side: int, radii, spread: float = DEFAULT_SPREAD,
                 min_spread: float = MIN_SPREAD) -> np.ndarray:
    """Normal flank displacement per unit reduced coordinate, ``A = F^T V`` (J, n) [m per unit].

    Row j: patch-weighted mean normal displacement (into the tooth) at ``radii[j]`` for a unit
    value of each reduced coordinate (frame ``u_x, u_y, theta``, then the modes); equally the
    generalised force per newton of contact force there.
    """
    F, *_ = flank_patch_loads(body.model, gear, tooth, side, radii, spread, min_spread)
    return F.T @ body.basis


@dataclass
class FlankSamples:
    """Unit patch loads at the same radii on the flanks of every tooth, each restricted to its flank's dofs.

        They turn a displacement field into patch-weighted normal flank displacements at every tooth
        at once.

        Attributes
        ----------
        radius : ndarray (J,)
            Contact radii [m].
        sides : tuple of int
            Flank sides, in the order of the second index of :meth:`sample`.
        dofs : list (sides) of list (z) of ndarray
            Dofs of each flank (sorted).
        loads : list (sides) of list (z) of ndarray (J, ndofs of the flank)
            Load values on those dofs [N per N], one row per radius (unit resultant).
        width, lo, hi : dict[int, ndarray (J,)]
            Half-widths [m] and clipped support [widths] per side (tooth 0's, every tooth alike).
        ndofs : int
            Dofs of the model.
    """

    radius: np.ndarray
    sides: tuple
    dofs: list
    loads: list
    width: dict
    lo: dict
    hi: dict
    ndofs: int
    support: np.ndarray | None = None

    @property
    def teeth(self) -> int:
        return len(self.dofs[0])

    def nearest(self, side_index: int, tooth: int) -> np.ndarray | None:
        """Radius indices (J,) that stand for those of a faulty flank (``support``): each radius
        the flank has no patch at (material removed) takes its nearest radius with one; None for a
        flank with a patch at every radius (or none at all: a tooth missing to the root)."""
        if self.support is None:
            return None
        ok = self.support[side_index, tooth % self.teeth]
        if ok.all() or not ok.any():
            return None
        have = np.flatnonzero(ok)
        j = np.arange(ok.size)
        return have[np.abs(j[:, None] - have[None, :]).argmin(axis=1)]

    def load_vectors(self, side: int, tooth: int) -> np.ndarray:
        """Full load vectors (ndofs, J) of the patches on one flank [N per N]."""
        i = self.sides.index(side)
        k = tooth % self.teeth
        F = np.zeros((self.ndofs, self.radius.size))
        F[self.dofs[i][k]] = self.loads[i][k].T
        return F

    def sample(self, U) -> np.ndarray:
        """Patch-weighted normal displacement of every flank point, array (z, len(sides), J,
        k), for displacement fields ``U`` (ndofs, k) [m per unit of U's columns]."""
        U = np.asarray(U, float)
        out = np.zeros((self.teeth, len(self.sides), self.radius.size, U.shape[1]))
        for i in range(len(self.sides)):
            for k in range(self.teeth):
                out[k, i] = self.loads[i][k] @ U[self.dofs[i][k]]
                idx = self.nearest(i, k)
                if idx is not None:
                    out[k, i] = out[k, i][idx]
        return out


def flank_samples(model, gear, radii, sides=SIDES, spread: float = DEFAULT_SPREAD,
                  min_spread: float = MIN_SPREAD, faulty=(), direction: str = "normal") -> FlankSamples:
    """The unit patch loads of :func:`flank_patch_loads` at ``radii`` on every tooth's flanks.

    ``direction = "tangential"``: the same patches pushing along the flank tangent ``R n_in``
    (n_in the normal into the tooth, R the turn by +90 degrees) instead of ``n_in``: sampled
    fields give the patch-weighted mean tangential flank displacement (:func:`tangential_table`).

    The patch pressure depends on the radius only, so one assembly over the flanks of all
    teeth per radius gives every tooth's load at once; each tooth's part is normalised by its
    own resultant. Same loads as :func:`flank_patch_loads` per tooth (patch half-widths from
    the flank range of the first tooth not in ``faulty``, tooth 0 of a healthy gear), about z
    times faster.

    ``faulty``: teeth whose flanks may have lost material (a missing tooth, a chip): where such
    a flank carries less than :data:`MIN_SUPPORT` of a healthy flank's patch resultant (or has no
    flank left) it gets no patch, ``support`` is False there, and :meth:`FlankSamples.sample`
    gives those radii the values of the nearest radius with a patch.
    """
    from skfem import FacetBasis, Functional, LinearForm

    if direction not in ("normal", "tangential"):
        raise ConfigError(f"direction = {direction!r}: must be 'normal' or 'tangential'")
    tangential = direction == "tangential"
    radii = np.atleast_1d(np.asarray(radii, float))
    L, rb, m = model.thickness, gear.rb, gear.module
    faulty = sorted({int(k) % gear.z for k in faulty})
    ref = reference_tooth(gear.z, faulty)
    support = np.ones((len(sides), gear.z, radii.size), bool) if faulty else None
    all_dofs, all_loads, width, los, his = [], [], {}, {}, {}
    for si, side in enumerate(sides):
        names = [flank_group(gear, k, side) for k in range(gear.z)]
        missing = [n for k, n in enumerate(names) if n not in model.mesh.boundaries and k not in faulty]
        if missing:
            raise ConfigError(f"mesh of {gear.name} has no boundary {missing[0]!r}")
        facets = [np.asarray(model.mesh.boundaries.get(n, np.zeros(0, np.int64))) for n in names]
        tooth_of_facet = np.repeat(np.arange(gear.z), [f.size for f in facets])
        fb = FacetBasis(model.mesh, model.basis.elem, facets=np.concatenate(facets), intorder=8)
        dofs = [np.sort(model.nodal_dofs(model.node_sets[n]).ravel()) if n in model.node_sets
                else np.zeros(0, np.int64) for n in names]
        loads = [np.zeros((radii.size, d.size)) for d in dofs]
        S_lo, S_hi = flank_arc_range(model, gear, side, ref)
        w_s, lo_s, hi_s = np.zeros(radii.size), np.zeros(radii.size), np.zeros(radii.size)
        for j, r in enumerate(radii):
            Sc = (r * r - rb * rb) / (2.0 * rb)
            if not (S_lo - 1e-9 <= Sc <= S_hi + 1e-9):
                raise ConfigError(f"{gear.name}: contact radius {r*1e3:.6g} mm lies off the "
                                  "meshed flank")
            w = min(spread * m, max(min_spread * m, min(Sc - S_lo, S_hi - Sc)))
            w_s[j], lo_s[j], hi_s[j] = w, max(-1.0, (S_lo - Sc) / w), min(1.0, (S_hi - Sc) / w)

            def pfun(x, Sc=Sc, w=w):
                sx = (x[0] ** 2 + x[1] ** 2 - rb * rb) / (2.0 * rb) - Sc
                return np.clip(1.0 - (sx / w) ** 2, 0.0, None) ** 2

            per_facet = Functional(lambda v: pfun(v.x)).elemental(fb) * L
            tot = np.bincount(tooth_of_facet, weights=per_facet, minlength=gear.z)
            if faulty:
                for k in faulty:
                    if not tot[k] >= MIN_SUPPORT * tot[ref]:
                        support[si, k, j] = False
                        tot[k] = math.inf  # no patch: zero load
            if not np.all(tot > 0):
                raise ConfigError(f"{gear.name}: the patch at r = {r*1e3:.6g} mm has no support "
                                  f"on flank {names[int(np.argmin(tot))]}")

            @LinearForm
            def load(v, wq):
                if tangential:  # R n_in = (n_y, -n_x), n = wq.n the outward normal
                    return L * pfun(wq.x) * (wq.n[1] * v[0] - wq.n[0] * v[1])
                return -L * pfun(wq.x) * sum(wq.n[c] * v[c] for c in range(2))

            f = load.assemble(fb)
            for k in range(gear.z):
                loads[k][j] = f[dofs[k]] / tot[k]
        all_dofs.append(dofs)
        all_loads.append(loads)
        width[side], los[side], his[side] = w_s, lo_s, hi_s
    return FlankSamples(radius=radii, sides=tuple(sides), dofs=all_dofs, loads=all_loads,
                        width=width, lo=los, hi=his, ndofs=model.ndofs, support=support)


#: Smallest patch resultant a faulty tooth's flank must carry at a table radius, relative to a
#: healthy flank's, to get a patch there (below it the material is mostly removed).
MIN_SUPPORT = 0.25


def reference_tooth(z: int, faulty=()) -> int:
    """The first tooth not in ``faulty`` (tooth 0 of a healthy gear): its flank range sets the
    table radii and patch widths of every tooth.

    Raises
    ------
    ConfigError
        Every tooth faulty.
    """
    bad = {int(k) % z for k in faulty}
    for k in range(z):
        if k not in bad:
            return k
    raise ConfigError(f"all {z} teeth are faulty or next to a faulty tooth: no healthy flank left to "
                      "set the flank tables' radii")


def modal_table(body, gear, radii, sides=SIDES, spread: float = DEFAULT_SPREAD,
                min_spread: float = MIN_SPREAD, samples: FlankSamples | None = None) -> np.ndarray:
    """:func:`modal_shapes` of every tooth: array (z, len(sides), J, n) [m per unit].

    From :func:`flank_samples` (given, or built here): same result as :func:`modal_shapes` per
    tooth, about z times faster.
    """
    if samples is None:
        samples = flank_samples(body.model, gear, radii, sides, spread, min_spread)
    elif tuple(samples.sides) != tuple(sides) or not np.array_equal(samples.radius, radii):
        raise ConfigError("modal_table: the samples were taken at other radii or sides")
    return samples.sample(body.basis)


def tangential_table(body, gear, radii, columns, sides=SIDES, faulty=(), spread: float = DEFAULT_SPREAD,
                     min_spread: float = MIN_SPREAD) -> np.ndarray:
    """Tangential flank displacement per unit reduced coordinate ``columns`` (indices into the
    body's basis), array (z, len(sides), J, len(columns)) [m per unit]: the patch-weighted mean
    displacement along ``R n_in`` (n_in the normal into the tooth, R the turn by +90 degrees),
    with the patches of :func:`modal_table` (``faulty``: as :func:`flank_samples`). Equally the
    generalised force per newton of force along ``R n_in`` on the patch; what the tooth
    friction needs of the modal coordinates (:mod:`flexgear.dynamics.flexible.sliding`)."""
    samples = flank_samples(body.model, gear, radii, sides, spread, min_spread, faulty=faulty,
                            direction="tangential")
    return samples.sample(np.asarray(body.basis)[:, np.asarray(columns)])


@dataclass
class FlankTables:
    """Residual static compliance between flank points of every pair of teeth and sides, interface held.

        A loaded tooth ``k`` uses the tables of class ``k % period``: one class for a bore or a
        whole rim, ``z / gcd(z, n_bolts)`` for a bolted ring.

        Attributes
        ----------
        radius : ndarray (J,)
            Table radii [m], increasing (the same on both flanks).
        period : int
            Number of tooth classes.
        spread, near_field : dict[int, ndarray (J,)]
            Patch half-widths [m] and their half-plane near field [m/N] per side.
        self_residual : dict[int, ndarray (period, J)]
            Residual self compliance, near field removed [m/N].
        coupling_radius : ndarray (Jc,)
            Radii of the coupling tables [m] (every ``(J - 1) / (Jc - 1)``-th, both ends included).
        coupling : ndarray (period, 2, 2, z, Jc, Jc)
            ``coupling[c, a, b, d, i, j]``: residual displacement of flank ``SIDES[a]`` of tooth
            ``c + d`` at coupling radius i per newton on flank ``SIDES[b]`` of tooth c at radius j
            [m/N] (d = z - 1 is the neighbour -1; the block d = 0, a = b includes the near field).
        self_static : dict[int, ndarray (period, J)]
            Full static self compliance, near field removed (modes + residual) [m/N].
        modal_fraction : dict[int, ndarray (period, J)]
            Share of the raw static self compliance carried by the kept modes [-].
        depth : float
            Near-field reference depth [m].
    """

    radius: np.ndarray
    period: int
    spread: dict
    near_field: dict
    self_residual: dict
    coupling_radius: np.ndarray
    coupling: np.ndarray
    self_static: dict
    modal_fraction: dict
    depth: float
    info: dict = field(default_factory=dict)

    @property
    def teeth(self) -> int:
        """Number of teeth z."""
        return self.coupling.shape[3]

    def _check_r(self, r):
        r = np.asarray(r, float)
        lo, hi = self.radius[0], self.radius[-1]
        if np.any(r < lo - 1e-12) or np.any(r > hi + 1e-12):
            raise ConfigError(f"radius {np.min(r)*1e3:.6g}..{np.max(r)*1e3:.6g} mm outside the "
                              f"table range {lo*1e3:.6g}..{hi*1e3:.6g} mm")
        return r

    def self_compliance(self, side: int, r, tooth: int = 0):
        """Residual self compliance of ``tooth`` at radius ``r`` (cubic spline in r) [m/N]."""
        from scipy.interpolate import CubicSpline

        r = self._check_r(r)
        return CubicSpline(self.radius, self.self_residual[side][tooth % self.period])(r)

    def residual_compliance(self, d: int, side_out: int, side_in: int, r_out, r_in,
                            tooth: int = 0):
        """Residual displacement of flank ``side_out`` of tooth ``tooth + d`` at ``r_out`` per
        newton on flank ``side_in`` of ``tooth`` at ``r_in`` [m/N] (bicubic spline).

        Raises
        ------
        ConfigError
            For d = 0 on the same flank (that is :meth:`self_compliance`, near field removed).
        """
        from scipy.interpolate import RectBivariateSpline

        if side_out not in SIDES or side_in not in SIDES:
            raise ConfigError(f"sides {side_out!r}, {side_in!r}: must be +1 or -1")
        if d % self.teeth == 0 and side_out == side_in:
            raise ConfigError("d = 0 on the same flank: use self_compliance (near field removed)")
        r_out, r_in = self._check_r(r_out), self._check_r(r_in)
        c = self.coupling[tooth % self.period, SIDES.index(side_out), SIDES.index(side_in),
                          d % self.teeth]
        k = min(3, self.coupling_radius.size - 1)
        return RectBivariateSpline(self.coupling_radius, self.coupling_radius, c, kx=k, ky=k)(
            r_out, r_in, grid=False)

    @property
    def coupling_stride(self) -> int:
        """Table radii per coupling-table interval [-]."""
        return (self.radius.size - 1) // (self.coupling_radius.size - 1)


def coupling_stride(n_points: int, coupling_points: int) -> int:
    """Table radii per coupling-table interval, ``(n_points - 1) / (coupling_points - 1)``.

    Raises
    ------
    ConfigError
        coupling_points < 2, above n_points, or not dividing the table into whole intervals.
    """
    if isinstance(coupling_points, bool) or not isinstance(coupling_points, (int, np.integer)) \
            or not 2 <= coupling_points <= n_points or (n_points - 1) % (coupling_points - 1):
        raise ConfigError(f"coupling_points = {coupling_points!r}: must be an integer in 2..{n_points} with "
                          f"n_points - 1 = {n_points - 1} a multiple of coupling_points - 1 (the coupling "
                          f"radii are every k-th table radius), e.g. {DEFAULT_COUPLING_POINTS} with "
                          f"n_points = {DEFAULT_TABLE_POINTS}")
    return (n_points - 1) // (coupling_points - 1)


def table_radii(model, gear, n_points: int = DEFAULT_TABLE_POINTS, tooth: int = 0) -> np.ndarray:
    """Radii uniform in involute arc length over the meshed flank of ``tooth`` (both sides; a
    healthy tooth) [m]."""
    if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)) or n_points < 4:
        raise ConfigError(f"n_points = {n_points!r}: a flank table needs an integer >= 4 points")
    lo = max(flank_arc_range(model, gear, s, tooth)[0] for s in SIDES)
    hi = min(flank_arc_range(model, gear, s, tooth)[1] for s in SIDES)
    S = np.linspace(lo, hi, n_points)
    return np.sqrt(gear.rb ** 2 + 2.0 * gear.rb * S)


def flank_tables(body, gear, radii=None, *, n_points: int = DEFAULT_TABLE_POINTS,
                 spread: float = DEFAULT_SPREAD, min_spread: float = MIN_SPREAD,
                 depth: float = DEFAULT_DEPTH, samples: FlankSamples | None = None,
                 coupling_points: int | None = None, faulty=()) -> FlankTables:
    """Residual compliance tables of one symmetry period's teeth (both flanks) to every tooth's flanks.

        One static solve per loaded tooth class, side and table radius with the reduction's
        factorisation, minus the kept modes' part, sampled on all flanks (:class:`FlankSamples`).

        With ``faulty`` teeth (a faulty gear: the faults' teeth and their neighbours) cyclic
        symmetry no longer holds: every tooth is its own class (``period = z``). The faulty teeth
        are loaded each, and one healthy tooth per symmetry class, as far from them as possible,
        stands for the others of its class (:func:`shared_teeth`); a table from such a shared
        tooth to a faulty one is taken from the faulty tooth's own table by reciprocity (the
        residual compliance is symmetric), so every table that involves a faulty tooth is that
        of the faulty body.

        Parameters
        ----------
        body : ReducedBody
            With residual flexibility (any reductor).
        gear : SpurGear
        radii : array_like, optional
            Table radii [m], increasing; default :func:`table_radii` with ``n_points``.
        spread, min_spread, depth : float
            Patch half-width, its minimum and the near-field depth [modules].
        samples : FlankSamples, optional
            :func:`flank_samples` at ``radii`` on both sides (built here if not given).
        coupling_points : int, optional
            Radii of the coupling tables (:func:`coupling_stride`); default all table radii.
        faulty : sequence of int
            Teeth with their own tables (default none: a healthy gear).

        Returns
        -------
        FlankTables
    """
    import time

    t0 = time.perf_counter()
    if body.residual is None:
        raise ConfigError("body has no residual flexibility")
    model = body.model
    z = gear.z
    faulty = sorted({int(k) % z for k in faulty})
    if radii is None:
        radii = table_radii(model, gear, n_points, reference_tooth(z, faulty))
    radii = np.asarray(radii, float)
    if radii.ndim != 1 or radii.size < 4 or np.any(np.diff(radii) <= 0):
        raise ConfigError("radii: need >= 4 strictly increasing radii")
    if samples is None:
        samples = flank_samples(model, gear, radii, SIDES, spread, min_spread, faulty=faulty)
    elif tuple(samples.sides) != tuple(SIDES) or not np.array_equal(samples.radius, radii):
        raise ConfigError("flank_tables: the samples were taken at other radii or sides")
    res = body.residual
    m, J = gear.module, radii.size
    stride = coupling_stride(J, J if coupling_points is None else coupling_points)
    Jc = (J - 1) // stride + 1
    period = body.interface.tooth_period(z)
    shared = shared_teeth(z, period, faulty) if faulty else {}
    loaded = faulty + sorted(set(shared.values())) if faulty else list(range(period))
    coupling = np.zeros((len(loaded), 2, 2, z, Jc, Jc))
    out = {k: {} for k in ("near", "self", "static", "fraction")}
    modal_samples = samples.sample(res.modes).reshape(-1, res.omega2.size)  # (z 2 J, n_modes)
    for b, side in enumerate(SIDES):
        w, lo, hi = samples.width[side], samples.lo[side], samples.hi[side]
        near = np.array([halfplane_compliance(wj, depth * m, model.material, model.thickness,
                                              model.formulation, a, c)
                         for wj, a, c in zip(w, lo, hi)])
        out["near"][side] = near
        selfs, statics, fracs = [], [], []
        for n, c in enumerate(loaded):
            F0 = samples.load_vectors(side, c)
            U = res.static(F0)
            # the kept modes' part Phi Omega^-2 Phi^T F0 only where it is sampled: F0 lives on
            # one flank's dofs, and sampling is linear (the ring's 163 modes: 8 GFlop a tooth
            # class as full fields)
            rows = samples.dofs[samples.sides.index(side)][c % samples.teeth]
            PtF = res.modes[rows].T @ F0[rows]
            eta = PtF / res.omega2[:, None]
            raw = np.einsum("ij,ij->j", F0[rows], U[rows])
            raw_modal = np.einsum("ij,ij->j", PtF, eta)
            sampled = samples.sample(U) - (modal_samples @ eta).reshape(z, 2, J, J)
            at = np.roll(sampled, -c, axis=0).transpose(1, 0, 2, 3)  # (2, z, J out, J in)
            idx = samples.nearest(b, c)
            if idx is not None:  # radii where the faulty flank has no patch: the nearest one's
                at, raw, raw_modal = at[..., idx], raw[idx], raw_modal[idx]
            coupling[n, :, b] = at[..., ::stride, ::stride]
            if samples.support is not None and not samples.support[b, c].any():  # no flank left: rigid
                selfs.append(np.zeros(J))
                statics.append(np.zeros(J))
                fracs.append(np.zeros(J))
                continue
            selfs.append(np.diagonal(at[b, 0]) - near)
            statics.append(raw - near)
            fracs.append(raw_modal / raw if raw.all() else np.divide(raw_modal, raw, out=np.zeros_like(raw),
                                                                      where=raw != 0))
        out["self"][side] = np.array(selfs)
        out["static"][side] = np.array(statics)
        out["fraction"][side] = np.array(fracs)
    if faulty:
        coupling, out = _per_tooth(coupling, out, loaded, shared, faulty, z)
        period = z
    return FlankTables(radius=radii, period=period,
                       spread={s: samples.width[s].copy() for s in SIDES},
                       near_field=out["near"], self_residual=out["self"],
                       coupling_radius=radii[::stride].copy(), coupling=coupling,
                       self_static=out["static"], modal_fraction=out["fraction"],
                       depth=depth * m, info={"seconds": time.perf_counter() - t0,
                                              "n_modes": body.n_modes, "loaded_teeth": list(loaded)})


def shared_teeth(z: int, period: int, faulty) -> dict:
    """The healthy tooth whose tables stand for each tooth of a faulty gear outside ``faulty``:
    {tooth: its stand-in}, the stand-in of the same symmetry class (``tooth % period``) farthest
    from every faulty tooth (around the gear).

    Raises
    ------
    ConfigError
        A symmetry class with every tooth faulty (then nothing is shared: not expected for
        a fault and its neighbours).
    """
    bad = {int(k) % z for k in faulty}

    def gap(k):
        return min(min((k - f) % z, (f - k) % z) for f in bad)

    stand = {}
    for c in range(period):
        members = [k for k in range(z) if k % period == c and k not in bad]
        if members:
            stand[c] = max(members, key=lambda k: (gap(k), -k))
    return {k: stand[k % period] for k in range(z) if k not in bad}


def _per_tooth(coupling, out, loaded, shared, faulty, z):
    """Tables of every tooth (``period = z``) from those of the ``loaded`` teeth: a faulty tooth
    its own, another its stand-in's, with the tables to a faulty tooth by reciprocity,
    ``coupling[k, a, b, d] = coupling[k + d, b, a, -d]^T``."""
    row = {c: n for n, c in enumerate(loaded)}
    src = [row[k] if k in row and k not in shared else row[shared[k]] for k in range(z)]
    full = coupling[src]
    bad = set(faulty)
    for k in range(z):
        if k in bad:
            continue
        for d in range(1, z):
            f = (k + d) % z
            if f in bad:
                full[k, :, :, d] = coupling[row[f], :, :, (z - d) % z].transpose(1, 0, 3, 2)
    out = {"near": out["near"], **{key: {s: v[src] for s, v in out[key].items()}
                                    for key in ("self", "static", "fraction")}}
    return full, out
