"""FORMULATIONS: name -> formulations.protocol.Formulation, the formulations a dynamics run
can take by name (rp, romega and joint built in: formulations.builtin). `register` adds one
(docs/architecture.md, "Adding a formulation"), `unregister` removes it; the `formulation`
option's choices (core.options.FORMULATIONS) follow, with "auto" last."""

from __future__ import annotations

from casmech.core.options import FORMULATIONS as NAMES
from casmech.core.registry import Registry
from casmech.formulations.builtin import BUILT_IN

FORMULATIONS = Registry(BUILT_IN)


def _names_changed() -> None:
    NAMES.set((*FORMULATIONS, "auto"))


FORMULATIONS.on_change(_names_changed)
_names_changed()
