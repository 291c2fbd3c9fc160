"""results.csv numbers: shortest round-trip text, read back bit for bit."""

import numpy as np
import pytest

from casmech.errors import UsageError
from casmech.io import csv
from casmech.io.csv import read_csv, write_csv

SPECIAL = [0.0, -0.0, 0.03, 0.1 + 0.2, 1.0, 1 / 3, 1e16, 2.0**53 + 2, -1.5e-300, 5e-324,
           np.finfo(float).max, np.finfo(float).tiny, np.inf, -np.inf]


def bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


def table() -> np.ndarray:
    """Output times as a run makes them, special values, and random doubles of every scale."""
    rng = np.random.default_rng(7)
    times = np.arange(101) * 0.01
    random = rng.standard_normal(101) * 10.0 ** rng.integers(-300, 300, 101)
    special = np.resize(np.array(SPECIAL), 101)
    return np.column_stack([times, random, special, rng.random(101)])


def test_read_back_bit_for_bit(tmp_path):
    values = table()
    names, read = read_csv(write_csv(tmp_path / "results.csv", ["t", "a", "b", "c"], values))
    assert names == ["t", "a", "b", "c"]
    np.testing.assert_array_equal(bits(read), bits(values))  # -0.0 and the signs included


def significant(text: str) -> str:
    """The significant digits of a number's text: '-1.50e-3' -> '15'."""
    return text.lower().split("e")[0].lstrip("-").replace(".", "").strip("0")


def test_shortest_round_trip_text(tmp_path):
    values = table()
    path = write_csv(tmp_path / "results.csv", ["t", "a", "b", "c"], values)
    rows = [line.split(",") for line in path.read_text().splitlines()[1:]]
    assert rows[3][0] == "0.03"  # 3 * 0.01, not 0.029999999999999999 (%.17g)
    pairs = [(text, x) for row, numbers in zip(rows, values, strict=True)
             for text, x in zip(row, numbers, strict=True) if np.isfinite(x)]
    for text, x in pairs:
        shortest = next(f"{x:.{p}g}" for p in range(1, 18) if float(f"{x:.{p}g}") == x)
        assert len(significant(text)) <= len(significant(shortest)), (text, shortest)


def test_nan_is_written_and_read_as_nan(tmp_path):
    values = np.array([[0.0, np.nan], [0.01, 2.5]])
    _, read = read_csv(write_csv(tmp_path / "results.csv", ["t", "x"], values))
    np.testing.assert_array_equal(np.isnan(read), np.isnan(values))
    np.testing.assert_array_equal(read[~np.isnan(read)], values[~np.isnan(values)])


@pytest.mark.parametrize("chunk", [csv.CHUNK_VALUES, 7])  # one block of rows; many
def test_rows_with_and_without_special_values_keep_their_order(tmp_path, monkeypatch, chunk):
    """Rows holding NaN or an infinity are written apart from the others (orjson writes
    neither): every row stays in its place, in any memory layout and block size, for one
    column and none."""
    monkeypatch.setattr(csv, "CHUNK_VALUES", chunk)
    values = np.asfortranarray(table())
    values[[5, 50], 3] = [np.nan, -np.inf]
    _, read = read_csv(write_csv(tmp_path / "results.csv", ["t", "a", "b", "c"], values))
    np.testing.assert_array_equal(bits(read), bits(values))
    _, single = read_csv(write_csv(tmp_path / "one.csv", ["t"], values[:, :1]))
    np.testing.assert_array_equal(bits(single), bits(values[:, :1]))
    path = write_csv(tmp_path / "none.csv", [], np.zeros((3, 0)))
    assert path.read_text() == "\n\n\n\n"  # the header and three empty rows


def test_large_files_read_by_pandas_bit_for_bit(tmp_path, monkeypatch):
    """Above PANDAS_BYTES the rows come from pandas' parser: the same bits, special values
    included, as numpy's parser gives."""
    values = table()
    values[[5, 50], 3] = [np.nan, -np.inf]
    path = write_csv(tmp_path / "results.csv", ["t", "a", "b", "c"], values)
    _, by_numpy = read_csv(path)
    monkeypatch.setattr(csv, "PANDAS_BYTES", 0)
    _, by_pandas = read_csv(path)
    np.testing.assert_array_equal(bits(by_pandas), bits(values))
    np.testing.assert_array_equal(bits(by_pandas), bits(by_numpy))


@pytest.mark.parametrize("pandas", [False, True])
def test_a_row_cut_off_at_the_end_is_not_read(tmp_path, monkeypatch, pandas):
    """A run killed while it wrote may leave its last row cut short (no newline): the rows
    before it are read as written, the cut one not."""
    if pandas:
        monkeypatch.setattr(csv, "PANDAS_BYTES", 0)
    values = np.array([[0.0, 1.5, -2.25], [0.1, 3.0, 1e-300], [0.2, 4.0, 5.0]])
    path = write_csv(tmp_path / "results.csv", ["t", "a", "b"], values)
    whole = path.read_bytes()
    for cut in (len(whole) - 1, len(whole) - 4, whole.rfind(b"\n", 0, len(whole) - 1) + 1 + 2):
        path.write_bytes(whole[:cut])
        names, read = read_csv(path)
        assert names == ["t", "a", "b"]
        np.testing.assert_array_equal(read, values[:2])  # written exactly, read exactly
    path.write_bytes(whole[:whole.find(b"\n") + 4])  # the first row cut
    assert read_csv(path)[1].shape == (0, 3)


def test_a_file_from_elsewhere_is_read_whole(tmp_path):
    """Measurements written by another tool often end without a newline: every line is read."""
    path = tmp_path / "measured.csv"
    path.write_text("t,x\n0,1.5\n0.5,2.25")  # no newline after the last row
    _, read = read_csv(path, as_written=False)
    np.testing.assert_array_equal(read, [[0.0, 1.5], [0.5, 2.25]])  # exact decimal binaries
    times, columns = csv.read_measurements(path)
    np.testing.assert_array_equal(times, [0.0, 0.5])  # the last row kept


@pytest.mark.parametrize("text", ["t,a,b\n0,1,2\n0.1,1\n0.2,3,4\n", "t,a\n0,1\n0.1,x\n"])
def test_a_table_that_is_not_numbers_is_a_usage_error(tmp_path, text):
    path = tmp_path / "results.csv"
    path.write_text(text)
    with pytest.raises(UsageError, match=r"results.csv:3:\d+: .*; expected a table of numbers"):
        read_csv(path)
    path.write_bytes(b"\xb1\x00\xff,\n\x01")
    with pytest.raises(UsageError, match="not a table of numbers"):
        read_csv(path)


@pytest.mark.parametrize("width", [3, csv.ROW_BY_ROW + 5])
def test_rows_formatted_one_by_one_are_the_blocks_text(monkeypatch, width):
    """Wide rows are formatted row by row (ROW_BY_ROW), narrow ones as one block: both give
    the same bytes, special values' rows included."""
    rng = np.random.default_rng(3)
    values = rng.standard_normal((40, width)) * 10.0 ** rng.integers(-300, 300, (40, width))
    values[:, 0] = np.arange(40) * 0.01
    values[7, 1], values[9, -1], values[11, 2] = np.nan, -np.inf, -0.0
    as_written = csv.rows_text(values)
    monkeypatch.setattr(csv, "ROW_BY_ROW", 1)
    row_by_row = csv.rows_text(values)
    monkeypatch.setattr(csv, "ROW_BY_ROW", width + 1)
    as_a_block = csv.rows_text(values)
    assert row_by_row == as_a_block == as_written
    assert as_written.count(b"\n") == 40 and b"nan" in as_written and b"-inf" in as_written
