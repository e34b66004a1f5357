"""Per-tooth law tables read by the force kernels: the lookup of a contact's flank in a
:class:`~flexgear.dynamics.model.tables.ToothLawTable` (built by
:mod:`flexgear.dynamics.model.tooth_laws`), for the rigid IMPACT law (:func:`tooth_law`: stiffness
factor, face-width slices) and the compliant law (:func:`contact_slices`: series compliance [m/N],
face-width slices)."""
from __future__ import annotations

from ...kernels import kernel
from .laws import HEALTHY_TERMS, HERTZ_RECESS_A, HERTZ_RECESS_B, HERTZ_SERIES, HERTZ_WIDTH_A, HERTZ_WIDTH_B


@kernel(error_model="numpy", inline="always")
def tooth_point(teeth, m, g, tooth, side, r):
    """(i, t): the entry i of flank ``side`` of ``tooth`` of gear side g (0: A, 1: B) of mesh m in
    the :class:`~flexgear.dynamics.model.tables.ToothLawTable` ``teeth`` at the contact's distance
    r [m] from the toothing centre, and the fraction t towards entry i + 1 (linear in r, held
    beyond the table's ends); i = -1 for a healthy flank."""
    first = teeth.first[m, g]
    if first < 0:
        return -1, 0.0
    row = teeth.row[first + 2 * tooth + (0 if side > 0 else 1)]
    if row < 0:
        return -1, 0.0
    x = (r - teeth.r0[row]) / teeth.dr[row]
    last = teeth.count[row] - 1
    j = 0
    t = 0.0
    if x >= last:
        j = last - 1
        t = 1.0
    elif x > 0.0:
        j = int(x)
        t = x - j
    return teeth.start[row] + j, t


@kernel(error_model="numpy", inline="always")
def flank_law(teeth, law, healthy, m, g, tooth, side, r):
    """(l, width, recess [m]) of flank ``side`` of ``tooth`` of gear side g (0: A, 1: B) of mesh m
    at the contact's distance r [m] from the toothing centre (:func:`tooth_point`): l from the
    table column ``law`` of the contact law's own term (``teeth.factor``, ``teeth.series``);
    (``healthy``, 1, 0) for a healthy flank."""
    i, t = tooth_point(teeth, m, g, tooth, side, r)
    if i < 0:
        return healthy, 1.0, 0.0
    la, wa, ha = law[i], teeth.width[i], teeth.recess[i]
    return (la + t * (law[i + 1] - la), wa + t * (teeth.width[i + 1] - wa),
            ha + t * (teeth.recess[i + 1] - ha))


@kernel(error_model="numpy", inline="always")
def tooth_law(teeth, m, g, tooth, side, r):
    """(kappa, width, recess [m]) of the rigid IMPACT law at a flank (:func:`flank_law`: the
    stiffness factor); (1, 1, 0) for a healthy flank."""
    return flank_law(teeth, teeth.factor, 1.0, m, g, tooth, side, r)


@kernel(error_model="numpy", inline="always")
def contact_slices(meshes, m, ta, tb, sa, ra, rb, hp, k):
    """Write into row k of ``hp`` the compliant law's per-tooth terms (columns
    :data:`~.laws.HERTZ_SERIES` to :data:`~.laws.HERTZ_RECESS_B`) of a contact of mesh m between
    tooth ta of gear A (flank sa, at ra [m] from its toothing centre) and tooth tb of gear B (at
    rb; B's flank: sa, or -sa on an internal gear, as :func:`tooth_force`): the series compliance,
    the sum of both flanks' (a root crack), and each flank's outline width fraction and recess
    (a spall or chip over part of the face width); :data:`~.laws.HEALTHY_TERMS` where both flanks
    are healthy (the series compliance exactly 0.0)."""
    teeth = meshes.teeth
    if teeth.first.shape[0] == 0 or (teeth.first[m, 0] < 0 and teeth.first[m, 1] < 0):
        for c in range(5):
            hp[k, HERTZ_SERIES + c] = HEALTHY_TERMS[c]
        return
    ca, wa, ha = flank_law(teeth, teeth.series, 0.0, m, 0, ta, sa, ra)
    cb, wb, hb = flank_law(teeth, teeth.series, 0.0, m, 1, tb, -sa if meshes.internal[m] else sa, rb)
    hp[k, HERTZ_SERIES] = ca + cb
    hp[k, HERTZ_WIDTH_A] = wa
    hp[k, HERTZ_RECESS_A] = ha
    hp[k, HERTZ_WIDTH_B] = wb
    hp[k, HERTZ_RECESS_B] = hb
