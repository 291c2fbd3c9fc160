"""Functions a system keeps for later analyses (integrators, mapped row functions), in a
bounded store that drops its oldest entry when full."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import TypeVar

T = TypeVar("T")
_MISSING = object()


def kept(store: dict, key: Hashable, build: Callable[[], T], limit: int) -> T:
    """store[key], built by build() when missing; at `limit` entries the oldest goes first.
    (A hit hashes the key once: keys are records and CasADi Functions, hashed in Python.)"""
    found = store.get(key, _MISSING)
    if found is not _MISSING:
        return found
    if len(store) >= limit:
        store.pop(next(iter(store)))
    store[key] = found = build()
    return found
