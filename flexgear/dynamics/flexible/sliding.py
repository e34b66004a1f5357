"""The flanks' elastic sliding velocity and the tooth friction's load on the modal coordinates.

A flexible gear's modal coordinates q_i move its flank points along the flank tangent too:
``T_i(k, s, r)`` [1/sqrt(kg)], the patch-weighted mean displacement along ``R n_in`` (n_in the
normal into the tooth, R the turn by +90 degrees) per unit coordinate, tabulated like the normal
``A_i`` (:func:`flexgear.reduction.flank.tangential_table`, same patches, teeth, sides and
radii). At a contact with normal n (of the force on gear a) and tangent t = R n, gear a's
n_in = n and gear b's = -n, so the sliding speed gains ``T_a . q_a' + T_b . q_b'`` and the
friction force (-f t on a, +f t on b) has the generalised force ``-f T`` on each gear's modal
coordinates: the same rows, so the friction's power is -f v_s exactly.

Only the modal coordinates carry it: the condensed modes and the residual tables are normal
only (the friction's load does not deflect them, their tangential motion is not in v_s), and
the elastic displacement's turning with the frame (omega x u, of the order of the flank
deflection times omega) is left out. See the theory page *Compliant contact and condensation*,
section *Tooth friction*.
"""
from __future__ import annotations

import numpy as np

from ...errors import ConfigError
from ...kernels import kernel
from .flank import radius_cell


def tangential_shapes(cfg, model) -> tuple[np.ndarray, np.ndarray]:
    """``(offset, shape)``: per FlexTable row f of ``model`` (``model.flex[f]``) the start of its
    tangential table in ``shape`` (-1: no modal coordinates), laid out as
    ``FlexTable.dynamic_shape``: ``shape[offset[f] + ((k * 2 + si) * J + j) * m + i] = T_i``
    [1/sqrt(kg)]. Computed from the cached reductions (their FE model and basis), for the bodies
    with modal coordinates only."""
    from ...gears.modified import faulty_teeth
    from ...reduction.flank import SIDES, tangential_table
    from .reductions import body_reduction, reduce_flexible_gears

    offset = np.full(len(model.flex), -1, np.int64)
    if not any(fb.modes for fb in model.flex):
        return offset, np.zeros(0)
    reds = reduce_flexible_gears(cfg)
    names = [b.name for b in model.bodies]
    parts, start, done = [], 0, {}
    for f, fb in enumerate(model.flex):
        if not fb.modes:
            continue
        red = body_reduction(reds, names[fb.body], fb.attrs["gear"])
        nq = 0 if red is None else red.body.n_interface
        if red is None or fb.dynamic_shape.shape != red.modal[..., nq:nq + fb.modes].shape \
                or not np.array_equal(red.modal[..., nq:nq + fb.modes], fb.dynamic_shape) \
                or not np.array_equal(red.tables.radius, fb.radius):
            raise ConfigError(f"[lubrication] on flexible body {names[fb.body]}: its modal coordinates are not "
                              f"the first {fb.modes} modes of the gear's reduction; tooth friction needs their "
                              "tangential flank shapes")
        if id(red) in done:  # bodies sharing a reduction (the planets) share its table
            offset[f] = done[id(red)]
            continue
        own = faulty_teeth(red.faults, red.gear.z) if red.faults else ()
        T = tangential_table(red.body, red.gear, red.tables.radius, np.arange(nq, nq + fb.modes), SIDES, own)
        offset[f] = done[id(red)] = start
        parts.append(np.ascontiguousarray(T, float).ravel())
        start += parts[-1].size
    return offset, np.ascontiguousarray(np.concatenate(parts))


@kernel(error_model="numpy", inline="always")
def modal_range(flex, body):
    """(FlexTable row, first modal coordinate, modal coordinates) of body ``body``; (-1, 0, 0)
    for a body without modal coordinates."""
    for f in range(flex.body.shape[0]):
        if flex.body[f] == body and flex.modes[f] > 0:
            return f, flex.coordinate[f], flex.modes[f]
    return -1, 0, 0


@kernel(error_model="numpy", inline="always")
def tangential_flank(flex, offset, shape, body, k, s, r, rates, row):
    """Tangential elastic velocity ``sum_i T_i(k, s, r) q_i'`` [m/s] of tooth k, side s (+1 / -1),
    radius r [m] of body ``body`` (0 without modal coordinates or table; ``offset``, ``shape``:
    :func:`tangential_shapes`; radius interpolation as
    :func:`~flexgear.dynamics.flexible.flank.modal_flank`); adds ``T_i`` to ``row`` at the body's
    modal coordinates (its d v_s / dq' there)."""
    f, c0, m = modal_range(flex, body)
    if f < 0 or f >= offset.shape[0] or offset[f] < 0:
        return 0.0
    J = flex.points[f]
    j, w = radius_cell(flex.radius, flex.radius_offset[f], J, r)
    b = offset[f] + ((k * 2 + (0 if s > 0 else 1)) * J + j) * m
    u = 0.0
    for i in range(m):
        ti = (1.0 - w) * shape[b + i] + w * shape[b + m + i]
        u += ti * rates[c0 + i]
        row[c0 + i] += ti
    return u
