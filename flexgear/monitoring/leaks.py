"""What a shaft's residual holds besides its own gear: content its average does not cancel.

Two checks, each giving a number per shaft and a warning when it is large
(``docs/guide/monitoring.md``, *Which signal*):

* the halves of a noise-free record (:func:`flexgear.monitoring.tsa.half_record_change`): what
  is not synchronous with the shaft differs between them;
* the common factor of a spur pair (:func:`partner_share`): with g = gcd(z, z_partner) > 1 the
  two gears meet the same teeth again every z_partner / g turns of the shaft, so whatever
  repeats with the partner gear (its fault) repeats with the shaft too, at the orders
  ``m z / g``, and no number of averages removes it. A residual mostly at those orders is the
  partner's, noisy or not.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import user_stacklevel
from .tsa import tsa_amplitudes

__all__ = ["UNSTEADY", "PARTNER", "common_orders", "partner_share", "mostly_partner", "warn_leaks"]

#: A noise-free simulation's residual whose two halves of the record differ by more than this
#: fraction of its RMS holds content not synchronous with its shaft.
UNSTEADY = 0.1

#: A residual whose power at the common-factor orders exceeds what a broadband residual puts
#: there by more than this fraction of the rest (:func:`partner_share`) reads the partner: a
#: fifth of its power (noise moves the fraction by a few hundredths; guide *Monitoring*).
PARTNER = 0.2


def common_orders(teeth: int, partner_teeth: int, max_order: int, shaft_orders: int = 2) -> np.ndarray:
    """The residual's orders (above ``shaft_orders``, at most ``max_order``, not mesh harmonics
    ``k z``) at which the partner gear's own content stays in the shaft's average: the multiples
    of ``z / gcd(z, z_partner)``; empty for co-prime tooth counts."""
    step = teeth // math.gcd(teeth, partner_teeth)
    k = np.arange(step, max_order + 1, step)
    return k[(k % teeth != 0) & (k > shaft_orders)]


def partner_share(residual, teeth: int, partner_teeth: int, max_order: int,
                  shaft_orders: int = 2) -> tuple[float, float] | None:
    """``(share, broadband)``: the fraction of the residual's power at :func:`common_orders`, and
    the fraction a residual spread evenly over its orders would put there (a fault of the
    shaft's own gear, or noise, reads about that). None for co-prime tooth counts or a zero
    residual."""
    orders = common_orders(teeth, partner_teeth, max_order, shaft_orders)
    power = tsa_amplitudes(residual) ** 2
    k = np.arange(power.size)
    support = (k > shaft_orders) & (k <= max_order) & (k % teeth != 0)
    total = power[support].sum()
    if orders.size == 0 or not total > 0:
        return None
    return float(power[orders].sum() / total), float(orders.size / np.count_nonzero(support))


def mostly_partner(share: tuple[float, float] | None) -> bool:
    """Whether a :func:`partner_share` is well above the broadband one (by :data:`PARTNER` of the
    way to 1)."""
    return share is not None and share[0] > share[1] + PARTNER * (1.0 - share[1])


def warn_leaks(signal_path: str, path, done: dict, suggest_noise: bool, suggest_normal_force: bool) -> None:
    """Warn where shafts' residuals hold content not their own gear's: a noise-free record's
    halves differ (``leaky``), or a spur pair's residual sits at the common-factor orders
    (``partner``). ``done``: the shafts' averages; ``suggest_noise``, ``suggest_normal_force``:
    whether to suggest giving the sensor noise or analysing a mesh's normal force instead."""
    leaky = [name for name, sa in done.items() if sa.leaky]
    if leaky:
        ways = ["compare with a healthy record (--baseline, NA4)"]
        if suggest_noise:
            ways.append("give the sensor measurement noise (snr_db)")
        if suggest_normal_force:
            ways.append("analyse a mesh's normal_force")
        warnings.warn(f"{signal_path} (a noise-free simulation) of {path}: the residual of "
                      f"{', '.join(leaky)} differs between the record's two halves by more than {UNSTEADY:g} of its "
                      "RMS (residual_unsteady in indicators.json): it holds content not synchronous with that shaft, "
                      "which its average does not cancel (another gear's fault; the carrier sidebands of a planetary "
                      "set's signal heard in the fixed frame), and its FM4, NA4, M6A and M8A read that too; "
                      f"{', or '.join(ways)}", stacklevel=user_stacklevel())
    for name, sa in done.items():
        if sa.partner is None or not mostly_partner(sa.partner_share):
            continue
        other, z, zo = sa.partner
        g = math.gcd(z, zo)
        share, broad = sa.partner_share
        warnings.warn(f"{signal_path} of {path}: {share:.0%} of the residual power of {name} lies at its orders "
                      f"{z // g}, {2 * z // g}, ... (a broadband residual puts {broad:.0%} there), "
                      f"where {other}'s own content stays in {name}'s average: gcd({z}, {zo}) = {g}, so the pair meets "
                      f"the same teeth every {zo // g} turns of {name} and no number of averages cancels {other}'s "
                      f"fault there (partner_share in indicators.json); {name}'s FM4, NA4, M6A and M8A read {other}",
                      stacklevel=user_stacklevel())
