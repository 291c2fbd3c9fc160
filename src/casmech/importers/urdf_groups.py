"""Which URDF links make one casmech body, and which joints join the bodies.

- A link joined by a `fixed` joint is merged into its parent's body (fusestatic).
- A moving joint below which nothing has mass (every link of the child's subtree massless or
  without `<inertial>`) is locked at its initial value and its links merged into the parent:
  with no mass the dynamics cannot move them (their motion is not determined), and the visuals
  keep riding on the parent (a warning names the joint).
- A link that moves, has no mass of its own (with its fixed children) but carries massive
  links is an intermediate frame: the joints from the body above to the body below compose
  into one casmech joint (importers/joint_chains.py: a gimbal of three hinges is a spherical
  joint, two perpendicular hinges a universal one). A massless link carrying two moving
  branches cannot be composed (E400).
"""

from __future__ import annotations

from dataclasses import field

import numpy as np

from casmech.core.records import record
from casmech.importers.urdf_read import Reader
from casmech.importers.urdf_tree import Frame, Joint, Link, Tree


@record(frozen=False)
class Group:
    """Links welded together by fixed (or locked) joints: one casmech body (or the ground)."""

    head: str  # the link whose frame is the body's
    members: list[tuple[Link, Frame]] = field(default_factory=list)  # frames in head's frame
    fused: list[Joint] = field(default_factory=list)

    def mass_properties(self) -> tuple[float, np.ndarray, np.ndarray]:
        """Mass, centre of mass and inertia about it, in the head link's frame."""
        parts = [(m.inertial.mass, at * m.inertial.frame, m.inertial.tensor)
                 for m, at in self.members if m.inertial is not None and m.inertial.mass > 0]
        mass = sum(p[0] for p in parts)
        if mass <= 0:
            return 0.0, np.zeros(3), np.zeros((3, 3))
        centre = sum(m * f.origin for m, f, _ in parts) / mass
        inertia = np.zeros((3, 3))
        for m, f, tensor in parts:
            d = f.origin - centre
            inertia += f.rotation @ tensor @ f.rotation.T + m * (d @ d * np.eye(3) - np.outer(d, d))
        return mass, centre, inertia


@record(frozen=False)
class Plan:
    groups: dict[str, Group]  # link name -> its group (the root's is the ground's)
    heads: list[str]  # the links heading a body, in file order (parents first)
    chains: dict[str, list[Joint]]  # body head -> the joints from its parent body to it
    parents: dict[str, str]  # body head -> its parent body's head (the root: ground)
    locked: list[Joint]  # moving joints locked (nothing below them has mass)


def _own_mass(link: Link) -> float:
    return link.inertial.mass if link.inertial is not None else 0.0


def subtree_masses(tree: Tree) -> dict[str, float]:
    masses = {name: _own_mass(link) for name, link in tree.links.items()}
    for joint in reversed(tree.joints):  # children before parents
        masses[joint.parent] += masses[joint.child]
    return masses


def plan(reader: Reader, tree: Tree, positions: dict[str, float]) -> Plan:
    below = subtree_masses(tree)
    of = {tree.root: Group(tree.root, [(tree.links[tree.root], Frame(np.eye(3), np.zeros(3)))])}
    at = {tree.root: of[tree.root].members[0][1]}
    locked = []
    for joint in tree.joints:
        link = tree.links[joint.child]
        welded = joint.type == "fixed" or below[joint.child] <= 0
        if welded:
            group = of[joint.parent]
            placed = joint.origin
            if joint.type != "fixed":
                locked.append(joint)
                placed = joint.origin * joint.motion(positions.get(joint.name, 0.0))
            at[joint.child] = at[joint.parent] * placed
            group.fused.append(joint)
        else:
            group = Group(joint.child)
            at[joint.child] = Frame(np.eye(3), np.zeros(3))
        group.members.append((link, at[joint.child]))
        of[joint.child] = group
    moving = [j for j in tree.joints if j.type != "fixed" and j not in locked]
    virtual = {j.child for j in moving if of[j.child].mass_properties()[0] <= 0}
    for head in virtual:
        out = [j for j in moving if of[j.parent] is of[head]]
        if len(out) != 1:
            link, names = tree.links[head], ", ".join(j.name for j in out)
            raise reader.error(link.element, f"link[{head}]", f"link '{head}' has no mass and "
                               f"carries {len(out)} moving joints ({names}): it cannot be "
                               "merged into the joints around it",
                               "a massless link between two moving joints, or a link with mass",
                               code="E400", hint="give the link an <inertial> with a mass")
    chains, parents = {}, {}
    heads = [j.child for j in moving if j.child not in virtual]
    for head in heads:
        joint = tree.joint_of(head)
        chain = [joint]
        parent = of[joint.parent].head
        while parent in virtual:
            joint = tree.joint_of(parent)
            chain.insert(0, joint)
            parent = of[joint.parent].head
        chains[head], parents[head] = chain, parent
    for head in virtual:
        for link, _ in of[head].members:
            if link.visuals:
                reader.warn(link.visuals[0], f"link[{link.name}]", f"the visuals of the "
                            f"massless link '{link.name}' are not translated: it is merged into "
                            "the joints around it, not a body", code="E400")
    return Plan(of, heads, chains, parents, locked)
