"""Fixtures of the force element tests: the compiler tests' seeded generator."""

from tests.compiler.conftest import rng  # noqa: F401
