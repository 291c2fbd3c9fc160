"""casmech inspect MODEL.yaml: bodies and their coordinates in q, constraint rows by joint with
their YAML locations, DOF, rank and redundant rows (at the assembled configuration)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from casmech import api
from casmech.cli.common import add_overrides, overrides


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    add_overrides(parser)


def body_lines(functions) -> list[str]:
    """One line per body: where its r and p sit in q = [r_1..r_nb, p_1..p_nb]."""
    nb = functions.n_bodies
    width = max((len(name) for name in functions.body_names), default=4)
    lines = [f"coordinates: {functions.n_coordinates}  (q = [r_1..r_nb, p_1..p_nb]; "
             "ground has none)"]
    for k, (name, body) in enumerate(zip(functions.body_names, functions.ir.bodies, strict=True)):
        where = f"  {body.source}" if body.source else ""
        lines.append(f"  {name:<{width}}  r (x y z) q[{3 * k}:{3 * k + 3}]  "
                     f"p (e0..e3) q[{3 * nb + 4 * k}:{3 * nb + 4 * k + 4}]{where}")
    return lines


def groups(functions) -> list[tuple[str, Sequence[int]]]:
    """(heading, row indices): each joint in file order, then the normalization rows."""
    headed = [(f"joint '{j.name}' ({j.type}, {j.body_i} -> {j.body_j})", j.rows)
              for j in functions.joints]
    normalization = [k for k, row in enumerate(functions.rows) if row.kind == "normalization"]
    return headed + [("normalization (one per body)", normalization)]


def row_lines(functions, independent: set[int]) -> list[str]:
    """Every constraint row: index in phi, primitive, label, YAML file:line:col, redundancy."""
    lines = [f"constraint rows: {functions.n_rows} ({functions.n_joint_rows} joint rows + "
             f"{functions.n_bodies} normalization)"]
    for heading, rows in groups(functions):
        lines.append(f"  {heading}: {len(rows)} rows")
        for k in rows:
            row = functions.rows[k]
            label = row.label.split(": ", 1)[-1]
            flag = "   REDUNDANT" if k not in independent else ""
            lines.append(f"    [{k:>3}] {row.kind:<13} {label:<40} {row.source or ''}{flag}")
    return lines


def run(args) -> int:
    model = api.load(args.model, overrides(args.set))
    functions = api.compile(model, "interpreted")  # no build for a look at the structure
    report, assembled = api.check(functions)
    where = "assembled configuration" if assembled else "pose in the file (assembly failed)"
    print(f"{args.model}: {functions.n_bodies} bodies, {len(functions.joints)} joints, "
          f"{len(model.forces)} forces")
    print("\n".join(body_lines(functions)))
    print("\n".join(row_lines(functions, set(report.independent))))
    print(f"at the {where}:")
    print(report.summary())
    return 0
