"""A registry of named entries whose changes listeners follow: the table behind
casmech.elements.joint_types and casmech.elements.force_types (schema/spec.py rebuilds its YAML
unions on a
change)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
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
