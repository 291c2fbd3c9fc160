"""FORMULATIONS: name -> formulations.protocol.Formulation, the formulations a dynamics run
can take by name (rp, romega and joint built in: formulations.builtin). `register` adds one
(docs/architecture.md, "Adding a formulation"), `unregister` removes it; the `formulation`
option's choices (core.options.FORMULATIONS) follow, with "auto" last."""

from __future__ import annotations

from typing import Any

from casmech.core.options import FORMULATIONS as NAMES
from casmech.core.registry import Registry
from casmech.errors import UsageError
from casmech.formulations.builtin import BUILT_IN
from casmech.formulations.protocol import Formulation


class Formulations(Registry):
    """A Registry of Formulation entries; "auto" is the option's own value, not a name."""

    def register(self, entry: Any) -> None:
        if not isinstance(entry, Formulation):
            raise UsageError(f"a formulation is a casmech.formulations.protocol.Formulation, "
                             f"not a {type(entry).__name__}")
        if entry.name == "auto":
            raise UsageError("'auto' names the choice among the formulations; register the "
                             "formulation under another name")
        super().register(entry)


FORMULATIONS = Formulations(BUILT_IN)


def _names_changed() -> None:
    NAMES.set((*FORMULATIONS, "auto"))


FORMULATIONS.on_change(_names_changed)
_names_changed()
