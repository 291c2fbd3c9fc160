"""Functions a system keeps for later analyses (integrators, mapped row functions), in a
bounded store that drops its oldest entry when full."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import TypeVar

T = TypeVar("T")


def kept(store: dict, key: Hashable, build: Callable[[], T], limit: int) -> T:
    """store[key], built by build() when missing; at `limit` entries the oldest goes first."""
    if key not in store:
        if len(store) >= limit:
            store.pop(next(iter(store)))
        store[key] = build()
    return store[key]
