"""Where a fault shows in a force record: the event a figure's zoom is centred on."""
from __future__ import annotations

import numpy as np


#: A departure from the mesh-periodic force below this fraction of the force's range is no
#: fault event (a healthy set's carrier envelope departs by about 1e-3 of it).
EVENT_FLOOR = 0.01


def fault_event(t: np.ndarray, f: np.ndarray, period: float) -> float | None:
    """Time [s] of the largest departure of the force ``f`` at times ``t`` from the mean of its
    values one mesh ``period`` [s] before and after (a tooth fault acts once in many mesh
    periods, the healthy mesh ripple repeats every period), or None where the trace is shorter
    than two periods or no departure exceeds :data:`EVENT_FLOOR` of the force's range."""
    inner = (t - period >= t[0]) & (t + period <= t[-1])
    if not inner.any():
        return None
    e = np.abs(f - 0.5 * (np.interp(t - period, t, f) + np.interp(t + period, t, f)))
    e[~inner] = 0.0
    k = int(np.argmax(e))
    return float(t[k]) if e[k] > EVENT_FLOOR * np.ptp(f) else None


def window_start(t: np.ndarray, centre: float, duration: float) -> float:
    """Start [s] of a window of ``duration`` [s] centred on ``centre``, kept inside the times ``t``."""
    return float(min(max(centre - 0.5 * duration, t[0]), max(t[-1] - duration, t[0])))
