"""The option tables of docs/analyses.md#options, generated from casmech.core.options.

    python -m tests.options_reference        # rewrite the tables in docs/analyses.md

Each table sits between `<!-- options: NAME -->` and `<!-- end options -->` (NAME a class of
casmech.core.options); the text around them is written by hand. tests/integration/test_options.py
fails when a table differs from what the classes say now (an option added, renamed, its default,
range or meaning changed).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from casmech.core import options
from casmech.core.option_values import fields, is_options, meaning

DOC = Path(__file__).resolve().parents[1] / "docs" / "analyses.md"
BLOCK = re.compile(r"(<!-- options: (\w+) -->\n)(.*?)(<!-- end options -->)", re.S)
HEADER = "| key | default | range | what |\n|---|---|---|---|\n"
# the tables, in the order of the page: the top keys of `analysis:`, then each `solver:` block
CLASSES = ("DynamicsOptions", "ModalOptions", "DynamicsSolver", "Fallback", "JointCompile",
           "KinematicsSolver", "StaticsSolver", "ModalSolver", "AssemblySolver", "Assembly",
           "LinearAlgebra")


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _shown(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value:g}" if isinstance(value, float) else str(value)


def rows(name: str) -> list[str]:
    """One row per field of the class: its key, default, range (unit) and meaning; a nested
    class's row names its table."""
    kind = getattr(options, name)
    defaults = kind()
    out = []
    for field, (_, hint) in fields(kind).items():
        found = meaning(kind, field)
        if is_options(hint):
            out.append(f"| `{field}` |  |  | {_cell(found.doc)}: [{hint.__name__}]"
                       f"(#{hint.__name__.lower()}) |")
            continue
        span = found.range_text() + (f" [{found.unit}]" if found.unit else "")
        out.append(f"| `{field}` | `{_shown(getattr(defaults, field))}` | {_cell(span)} | "
                   f"{_cell(found.doc)} |")
    return out


def table(name: str) -> str:
    return HEADER + "\n".join(rows(name)) + "\n"


def documented(text: str) -> list[str]:
    return [match.group(2) for match in BLOCK.finditer(text)]


def regenerate(text: str) -> str:
    return BLOCK.sub(lambda m: m.group(1) + table(m.group(2)) + m.group(4), text)


def main() -> int:
    text = DOC.read_text(encoding="utf-8")
    new = regenerate(text)
    if new != text:
        DOC.write_text(new, encoding="utf-8")
        print(f"rewrote {DOC}")
    missing = sorted(set(CLASSES) - set(documented(new)))
    if missing:
        print(f"{DOC} has no table for {', '.join(missing)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
