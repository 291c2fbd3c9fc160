"""pydantic's plugin lookup, off in the command line's process unless the user chose
(docs/decisions/pydantic-plugins.md).

`turn_off()` sets PYDANTIC_DISABLE_PLUGINS=__all__ unless the variable is set. When it is
`__all__`, `1` or `true` (pydantic's own values for "no plugins"), it also puts a module of its
own under the name of pydantic's plugin loader, `pydantic.plugin._loader`, whose only import
at the top is `importlib.metadata` (with email, zipfile, csv and socket), before pydantic is
imported: its `get_plugins` returns no plugins while the variable says so, as pydantic's
does, and anything else (another value of the variable, any other name of the module)
imports pydantic's own loader in its place and reads it there.
"""

from __future__ import annotations

import importlib
import os
import sys
import types

LOADER = "pydantic.plugin._loader"
_OFF = ("__all__", "1", "true")  # the values for which pydantic's get_plugins returns ()


def turn_off() -> None:
    """No pydantic plugins unless the user set PYDANTIC_DISABLE_PLUGINS to something else."""
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")
    if os.environ["PYDANTIC_DISABLE_PLUGINS"] in _OFF and LOADER not in sys.modules:
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
