"""The spanning tree of a model's joints by name: which joint reaches which body from which.

The rule of the joint formulation (formulations/tree.py): breadth first from ground, visiting
each body's joints in file order; the first joint that reaches a body is its tree joint (the
body is its child) if its type has a tree motion (casmech.elements.joint_types) and the file
does not say `cut: true`. Posing also takes a joint whose coordinates follow one another
(a screw: joint_types.JointType.follows), which the joint formulation cuts. A body no tree
joint reaches from ground is a root (it floats), in file order of the bodies, and the search
goes on from it. The schema (a body's velocity that its joints' `initial:` rates give,
schema/initial.py) and the lowering (the bodies posed from those values, model/initial.py)
read it here.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

from casmech.core.records import record
from casmech.elements.joint_types import REGISTRY

GROUND = "ground"


@record
class Link:
    """A joint as the tree sees it."""

    name: str
    type: str
    body_i: str
    body_j: str
    cut: bool = False


@record
class TreeJoint:
    """A tree joint: the index of its link and the parent and child bodies it joins."""

    index: int  # the joint's index among the links
    parent: str
    child: str

    def reversed(self, links: Sequence[Link]) -> bool:
        """Whether the joint's body_i is the child (it is traversed from body_j)."""
        return links[self.index].body_i != self.parent


@record
class Tree:
    """The spanning tree by name: its tree joints (parents before children) and the bodies
    that float."""

    joints: tuple[TreeJoint, ...]  # parents before children
    roots: tuple[str, ...]  # bodies that float (no tree joint reaches them from ground)

    def root_of(self) -> dict[str, str]:
        """body -> the root of its part of the tree (ground or a floating body)."""
        found = {root: root for root in self.roots} | {GROUND: GROUND}
        for joint in self.joints:
            found[joint.child] = found[joint.parent]
        return found


def _can_be_tree(link: Link) -> bool:
    entry = REGISTRY.get(link.type)
    return entry is not None and (entry.motion is not None or bool(entry.follows)) \
        and not link.cut \
        and link.body_i != link.body_j


def spanning_tree(bodies: Sequence[str], links: Sequence[Link]) -> Tree:
    """The tree of the module docstring over `bodies` (names, file order) and `links`."""
    at: dict[str, list[int]] = {}
    for k, link in enumerate(links):
        for body in dict.fromkeys((link.body_i, link.body_j)):
            at.setdefault(body, []).append(k)
    reached, tree, roots = {GROUND}, [], []

    def search(start: str) -> None:
        queue = deque([start])
        while queue:
            body = queue.popleft()
            for k in at.get(body, ()):
                link = links[k]
                other = link.body_j if link.body_i == body else link.body_i
                if other in reached or not _can_be_tree(link):
                    continue
                tree.append(TreeJoint(k, body, other))
                reached.add(other)
                queue.append(other)

    search(GROUND)
    for body in bodies:
        if body not in reached:
            roots.append(body)
            reached.add(body)
            search(body)
    return Tree(tuple(tree), tuple(roots))
