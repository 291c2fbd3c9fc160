"""Write the JSON Schema of the model format (for editors and other tools).

python -m casmech.schema.export [PATH]    # default: casmech/schema/casmech.schema.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from casmech.schema.spec import ModelSpec

DEFAULT_PATH = Path(__file__).with_name("casmech.schema.json")


def schema_text() -> str:
    """The JSON Schema of ModelSpec, as committed (sorted keys, 2-space indent, final newline)."""
    return json.dumps(ModelSpec.model_json_schema(), indent=2, sort_keys=True) + "\n"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    path = Path(args[0]) if args else DEFAULT_PATH
    path.write_text(schema_text(), encoding="utf-8")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
