"""Model texts several test modules write into their temporary folders."""

from __future__ import annotations


def pendulum(driver: str | None = None, analysis: str | None = None) -> str:
    """A bar of 1 kg hanging 1 m below a revolute pivot about x: `driver: {angle: DRIVER}`
    (None: undriven) and `analysis: {type: ANALYSIS, t_end: 1, output_step: 0.1}` (None: no
    analysis block)."""
    text = ("casmech: 1\nname: pend\nbodies:\n"
            "  - {name: bar, mass: 1, inertia: [1, 1, 1], position: [0, 0, -1]}\n"
            "joints:\n  - name: pivot\n    type: revolute\n    body_i: ground\n"
            "    body_j: bar\n    at: [0, 0, 0]\n    axis: [1, 0, 0]\n")
    if driver is not None:
        text += f"    driver: {{angle: {driver}}}\n"
    if analysis is not None:
        text += f"analysis: {{type: {analysis}, t_end: 1, output_step: 0.1}}\n"
    return text
