"""The FMU fixtures (tests/helpers/fmu.py) for the tests of this folder."""

from tests.helpers.fmu import private_cache, toolchain  # noqa: F401
