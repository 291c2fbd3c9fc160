"""pydantic's plugin loader stands aside while plugins are off
(docs/decisions/pydantic-plugins.md).

When PYDANTIC_DISABLE_PLUGINS is `__all__`, `1` or `true` (pydantic's own values for "no
plugins"; the command line sets `__all__` unless the user chose), `stand_aside()` (called as
core.spec_base, the format's first pydantic module, is imported) puts a module of its own under
the name of pydantic's plugin loader, `pydantic.plugin._loader`, which pydantic imports when it
builds its first validator and whose imports at the top pull in `importlib.metadata` (with
email, zipfile, csv and socket). Its `get_plugins` returns no plugins while the variable says
so, as pydantic's does; anything else (another value of the variable by then, any other name
of the module) imports pydantic's own loader in its place and reads it there.
"""

from __future__ import annotations

import importlib
import os
import sys
import types

LOADER = "pydantic.plugin._loader"
_OFF = ("__all__", "1", "true")  # the values for which pydantic's get_plugins returns ()


def stand_aside() -> None:
    """The stand-in in pydantic's loader's place, while plugins are off and pydantic has not
    imported its own."""
    if os.environ.get("PYDANTIC_DISABLE_PLUGINS") in _OFF and LOADER not in sys.modules:
        sys.modules[LOADER] = _Loader(LOADER, __doc__)


class _Loader(types.ModuleType):
    """Stands for pydantic's plugin loader until a plugin could be loaded."""

    def get_plugins(self):
        if os.getenv("PYDANTIC_DISABLE_PLUGINS") in _OFF:
            return ()
        return _own().get_plugins()

    def __getattr__(self, name: str):
        if name.startswith("__"):  # (the import system's questions: no such attribute)
            raise AttributeError(name)
        return getattr(_own(), name)


def _own() -> types.ModuleType:
    """pydantic's own plugin loader, imported in the stand-in's place."""
    if isinstance(sys.modules.get(LOADER), _Loader):
        del sys.modules[LOADER]
    return importlib.import_module(LOADER)
