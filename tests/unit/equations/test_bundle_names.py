"""equations.bundle_names: the bundle's function names without the builder, the same names in
the same order as equations.system.DEFINITIONS, and what backends.deferred reads of them."""

from casmech.backends import deferred
from casmech.equations import bundle_names, system


def test_the_names_are_the_builders_in_its_order():
    assert bundle_names.NAMES == tuple(system.DEFINITIONS)


def test_the_rest_of_a_joint_trees_bundle_is_every_other_function_in_the_bundles_order():
    assert deferred.rest() == tuple(name for name in system.DEFINITIONS
                                    if name not in deferred.READ)
    assert set(deferred.rest()) | set(deferred.READ) == set(system.DEFINITIONS)
