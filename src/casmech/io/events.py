"""events.csv: the events of a dynamics run (runtime.events), one row each in time order:
t, name, then every results column at the event; and the same rows for metadata.json."""

from __future__ import annotations

from pathlib import Path

from casmech.core.atomic import atomic

FILE = "events.csv"


def write_events(path: str | Path, names: list[str], rows: list[list]) -> Path:
    """Write atomically; numbers as results.csv writes them (repr: they read back exactly),
    the event's name as written in the model (a valid name: no comma, no quote)."""
    path = Path(path)
    with atomic(path, newline="") as handle:
        handle.write(",".join(names) + "\n")
        handle.writelines(",".join(value if isinstance(value, str) else repr(float(value))
                                   for value in row) + "\n" for row in rows)
    return path


def metadata_rows(records, names: list[str], rows: list[list]) -> list[dict]:
    """The events for metadata.json: name, t, direction, action and the row's values by
    column."""
    return [{"name": record.name, "t": record.t, "direction": record.direction,
             "action": record.action,
             "values": dict(zip(names[2:], (float(v) for v in row[2:]), strict=True))}
            for record, row in zip(records, rows, strict=True)]
