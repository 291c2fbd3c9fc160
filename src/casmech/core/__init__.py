"""The bottom layer: rotation math and the names of the mechanism's coordinates.

Imports numpy and CasADi only, never another casmech package, so that `schema/`, `equations/`
and the joint registry (`casmech.elements.joint_types`) can all read it.

    euler        A(p), G(p), E(p), B(p, a_bar), skew(v) of Euler parameters
    quaternions  quaternion products, axis rotations, rotation matrix -> quaternion, angles
    motions      the relative motion a tree joint allows (joint-coordinate formulation)
    states       names of the state a force law or event reads (`bar.vx`, `pivot.angle`)
    values       `constant`: IR data (numbers or CasADi symbols) as CasADi matrices
"""
