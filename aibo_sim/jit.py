"""numba's ``njit`` with the compiled code cached on disk where numba finds a place to write it
(beside the module, or the user's cache folder), and compiled anew in each process where it finds
none: a system-wide install run by a user without a writable home (a container's ``--user``)."""

from __future__ import annotations

import numba


def compiled(**options):
    """A decorator: ``numba.njit(cache=True, **options)``, or without the cache where numba has
    nowhere to keep it ("cannot cache function ...: no locator available")."""

    def decorate(function):
        try:
            return numba.njit(cache=True, **options)(function)
        except RuntimeError:
            return numba.njit(**options)(function)

    return decorate
