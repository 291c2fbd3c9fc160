"""The code-generation fixtures (tests/helpers/codegen.py) and the background build's
(tests/helpers/background.py) for the tests of this folder."""

from tests.helpers.background import building  # noqa: F401
from tests.helpers.codegen import (  # noqa: F401
    build_dir,
    builds,
    cache_root,
    compiled,
    interpreted,
    model,
    private_cache,
    toolchain,
)
