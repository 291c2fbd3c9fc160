"""The built-in force elements' code, one module per family; casmech.elements.force_types holds
their
registry entries. Bottom layer: imports casmech.core, casmech.elements.joint_types,
casmech.core.spec_base
and third-party libraries only (tests/unit/test_layering.py).

    terms         shared terms: points of frames, the spring law, a point force, a torque
    springs       tsda, rsda
    loads         force, torque
    bushing       bushing
    contact_spec  the contacts' checks
    specs         the YAML classes of them all, imported when the schema first needs one
    contact       the contacts' laws and lowering (sphere_plane, sphere_sphere, points_plane,
                  capsule_plane)
"""
