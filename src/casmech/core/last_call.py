"""A function's value for the arguments it was called with last, kept by their identity.

A run asks the same question of the same frozen records several times (its model's IR, cache
key and tree test are each wanted by the cache lookup and again by the load); `last_call(make)`
answers the repeat without computing it again. The arguments are compared by identity (`is`),
never by value, so a record equal to the last but another object is computed anew. The kept
pair is one tuple read and replaced whole: threads asking for different arguments at once each
get the value of their own arguments (at worst computed twice).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")


class LastCall(Generic[T]):
    """make(*arguments), kept for the arguments given last (module docstring)."""

    def __init__(self, make: Callable[..., T]):
        self._make = make
        self._kept: tuple[tuple, T] | None = None

    def __call__(self, *arguments) -> T:
        kept = self._kept  # one read: another thread may replace it meanwhile
        if kept is not None and len(kept[0]) == len(arguments) and all(
                given is asked for given, asked in zip(kept[0], arguments, strict=True)):
            return kept[1]
        value = self._make(*arguments)
        self._kept = (arguments, value)
        return value


def last_call(make: Callable[..., T]) -> LastCall[T]:
    """`make` kept for the arguments it was called with last."""
    return LastCall(make)
