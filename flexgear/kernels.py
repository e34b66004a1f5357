"""The one way flexgear declares a compiled kernel: ``@kernel(...)``, numba's ``njit`` with
the on-disk cache.

Every compiled function of the package is declared here, so that the cache's rules (where it
lives, when it is stale, how concurrent processes share it) are set in one place.
"""
from __future__ import annotations

import numba as nb

#: Every dispatcher declared with ``@kernel``, in declaration order.
KERNELS: list = []


def kernel(**options):
    """Decorator: ``numba.njit(cache=True, **options)``, registered in :data:`KERNELS`."""

    def declare(fn):
        dispatcher = nb.njit(cache=True, **options)(fn)
        KERNELS.append(dispatcher)
        return dispatcher

    return declare
