"""events.csv (io/events.py): what it writes reads back exactly."""

import csv

from casmech.io.events import metadata_rows, write_events
from casmech.runtime.events import EventRecord


def test_rows_read_back_exactly(tmp_path):
    names = ["t", "name", "bar.x", "bar.z"]
    rows = [[0.1 + 0.2, "first", 1 / 3, -0.0], [2.5e-300, "second", 1e300, 7.0]]
    path = write_events(tmp_path / "events.csv", names, rows)
    with open(path, newline="") as handle:
        read = list(csv.reader(handle))
    assert read[0] == names
    assert [[float(r[0]), r[1], *map(float, r[2:])] for r in read[1:]] == rows
    assert not list(tmp_path.glob(".*.tmp"))  # written atomically: no temporary left


def test_metadata_rows_name_every_value():
    records = [EventRecord("low", 0.5, "falling", "stop")]
    [row] = metadata_rows(records, ["t", "name", "ball.z"], [[0.5, "low", -1.25]])
    assert row == {"name": "low", "t": 0.5, "direction": "falling", "action": "stop",
                   "values": {"ball.z": -1.25}}
