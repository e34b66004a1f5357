"""Unit conversion at the edge: ADAMS model units (N, mm, s) -> SI.

ADAMS evaluates the IMPACT law in the model's units. With the paper's model in N and mm and the
force exponent e, a stiffness K given in N/mm^e means F[N] = K (delta[mm])^e, so in SI
K_SI = K * 1000^e N/m^e. Damping C in N s/mm becomes 1000 C N s/m; the penetration depth d in
mm becomes d / 1000 m. These are the only conversions in flexgear; everything else is SI.
"""
from __future__ import annotations

from .errors import ConfigError

MM = 1e-3  # metres per millimetre

UNIT_SYSTEMS = ("SI", "N-mm")


def impact_to_si(stiffness: float, exponent: float, damping: float, depth: float, units: str):
    """Convert IMPACT parameters from ``units`` to SI.

    Parameters
    ----------
    stiffness : float
        K in N/m^e ("SI") or N/mm^e ("N-mm").
    exponent : float
        Force exponent e [-] (unchanged).
    damping : float
        C in N s/m ("SI") or N s/mm ("N-mm").
    depth : float
        Penetration depth d at which damping is full, in m ("SI") or mm ("N-mm").
    units : str
        "SI" or "N-mm".

    Returns
    -------
    (K [N/m^e], e, C [N s/m], d [m])
    """
    if units == "SI":
        return float(stiffness), float(exponent), float(damping), float(depth)
    if units == "N-mm":
        return float(stiffness) * (1.0 / MM) ** exponent, float(exponent), float(damping) / MM, float(depth) * MM
    raise ConfigError(f"contact.units = {units!r}: must be one of {UNIT_SYSTEMS}")
