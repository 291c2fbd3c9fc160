"""A registry of named entries whose changes listeners follow: the table behind
casmech.elements.joint_types and casmech.elements.force_types (schema/spec.py rebuilds its YAML
unions on a
change)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any


class Registry(dict):
    """name -> entry (anything with a `name`), in registration order."""

    def __init__(self, entries: Iterable[Any] = ()):
        super().__init__((entry.name, entry) for entry in entries)
        self.listeners: list[Callable[[], None]] = []

    def register(self, entry: Any) -> None:
        """Add (or replace) an entry; every stage sees it from now on."""
        self[entry.name] = entry
        self._changed()

    def unregister(self, name: str) -> None:
        del self[name]
        self._changed()

    def on_change(self, listener: Callable[[], None]) -> None:
        """Call `listener()` after every register/unregister."""
        self.listeners.append(listener)

    def _changed(self) -> None:
        for listener in self.listeners:
            listener()


class Names(Sequence):
    """A sequence of names that a registry of a higher layer keeps current (the choices of an
    option whose values are registered there: core.options.FORMULATIONS), with listeners as
    a Registry has (the YAML schema follows it)."""

    def __init__(self, names: Iterable[str]):
        self._names = tuple(names)
        self.listeners: list[Callable[[], None]] = []

    def set(self, names: Iterable[str]) -> None:
        names = tuple(names)
        if names != self._names:
            self._names = names
            for listener in self.listeners:
                listener()

    def on_change(self, listener: Callable[[], None]) -> None:
        """Call `listener()` after every change of the names."""
        self.listeners.append(listener)

    def __getitem__(self, index):
        return self._names[index]

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"Names({self._names!r})"
