"""runtime.nonfinite.check_states: the first row of a block with a value that is not finite,
whether the block is checked as one array (small) or state by state (large), against a
value-by-value scan with math.isfinite; all_finite against an entrywise check, its sums never
longer than PIECE (OpenBLAS sums longer vectors in threads), states viewing one array summed
as that array."""

import math

import numpy as np
import pytest

from casmech.runtime import nonfinite
from casmech.runtime.nonfinite import ONE_ARRAY, PIECE, all_finite, check_states


def _scan(times, *blocks) -> int | None:
    """The first row holding a non-finite value, by a plain loop over every value."""
    for row in range(len(times)):
        values = [times[row]] + [v for block in blocks for v in block[row]]
        if not all(math.isfinite(v) for v in values):
            return row
    return None


@pytest.mark.parametrize("rows", [0, 1, 7, ONE_ARRAY, ONE_ARRAY + 1, 3 * ONE_ARRAY])
def test_the_first_bad_row_is_found_in_small_and_large_blocks(rows):
    rng = np.random.default_rng(rows)
    widths = (14, 14, 14, 0 if rows % 2 else 9)  # lam empty for a tree
    for trial in range(12):
        times = np.linspace(0.0, 1.0, rows)
        blocks = [rng.normal(size=(rows, w)) for w in widths]
        if rows and trial:  # trial 0: all finite
            for _ in range(int(rng.integers(1, 4))):
                where = int(rng.integers(0, 5))
                row = int(rng.integers(0, rows))
                bad = (np.nan, np.inf, -np.inf)[int(rng.integers(0, 3))]
                if where == 0 or not widths[where - 1]:
                    times[row] = bad
                else:
                    blocks[where - 1][row, int(rng.integers(0, widths[where - 1]))] = bad
        assert check_states(times, *blocks) == _scan(times, *blocks)


@pytest.mark.parametrize("rows", [1, 3, ONE_ARRAY + 5])
def test_finite_values_whose_sum_overflows_are_finite(rows):
    """Values near the largest float: their sum is infinite, every row is still finite."""
    big = np.full((rows, 6), 1.5e308)
    times = np.linspace(0.0, 1.0, rows)
    assert check_states(times, big, -big[:, :3], big, np.zeros((rows, 0))) is None
    big[rows - 1, 2] = np.inf
    assert check_states(times, big, big, big, big) == rows - 1


def test_all_finite_matches_an_entrywise_check_through_overflowing_sums():
    """all_finite against np.isfinite entry by entry: a NaN or an infinity in any
    array is found, opposite infinities whose sum is NaN too, and finite entries whose sum
    overflows are finite."""
    big = np.full(4, 1e308)  # finite entries, sum inf
    cases = [(np.zeros((3, 2)), np.zeros((0, 2))), (big, -big), (big, np.ones(2)),
             (np.array([1.0, np.nan]), np.ones(2)), (np.ones(2), np.array([np.inf])),
             (np.array([np.inf, -np.inf]),), (big, np.array([[np.nan]]))]
    # transposed and strided views (read in place or copied), a NaN or an infinity inside
    block = np.arange(12.0).reshape(3, 4)
    block[2, 1] = np.nan
    strided = np.ones((4, 6))
    strided[2, 4] = np.inf
    cases += [(block.T,), (block[:2].T,), (strided[:, ::2],), (strided[:, 1::3],),
              (np.full((3, 2), 1e200).T,)]
    for arrays in cases:
        expected = all(np.isfinite(a).all() for a in arrays)
        assert all_finite(*arrays) == expected, arrays


def test_the_check_itself_warns_nothing():
    """Sums that overflow or meet inf - inf are how the check finds out, not a NumPy warning
    for the user's terminal (an error here under the filter)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert all_finite(np.full(4, 1e308))
        # squares finite in each array, their total beyond the largest double
        assert all_finite(np.full(2, 1.2e154), np.full((1, 2), 1.2e154))
        assert not all_finite(np.array([np.inf, -np.inf, 1.0]))
        assert check_states(np.arange(3.0), np.full((3, 2), 1e308), np.array(
            [[1.0, 2.0], [np.inf, -np.inf], [0.0, 0.0]]), np.zeros((3, 2)),
            np.zeros((3, 0))) == 1


@pytest.fixture
def sums(monkeypatch) -> list[int]:
    """The length of every sum of squares all_finite takes from here on."""
    taken, original = [], nonfinite._SQUARES

    def squares(a, b):
        taken.append(a.size)
        return original(a, b)

    monkeypatch.setattr(nonfinite, "_SQUARES", squares)
    return taken


def test_long_arrays_are_summed_in_pieces_and_every_piece_counts(sums):
    """An array longer than PIECE is summed in pieces of at most PIECE entries (one BLAS
    thread), and a NaN or an infinity in any piece, the last one's among them, is found."""
    values = np.ones((3 * PIECE + 5) // 7 + 1, float)[:, None] * np.ones(7)  # (rows, 7)
    assert all_finite(values)
    assert sums and max(sums) <= PIECE and sum(sums) == values.size
    for where in (0, PIECE - 1, PIECE, values.size - 1):
        bad = values.copy()
        bad.flat[where] = (np.nan, np.inf)[where % 2]
        assert not all_finite(bad), where


def test_states_viewing_one_array_are_summed_as_that_array(sums):
    """The four states as views of one array no larger than them (the rows' C loop's
    outputs) take one sum besides the times'; any other states, one sum each; either way the
    first bad row is the scan's."""
    rows, widths = 5, (6, 6, 6, 4)
    one = np.arange(rows * sum(widths), dtype=float) / 7
    edges = np.cumsum([0, *widths]) * rows
    views = [one[a:b].reshape(rows, -1) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    times = np.linspace(0.0, 1.0, rows)
    assert check_states(times, *views) is None and len(sums) == 2
    views[3][2, 1] = np.nan  # (in the one array)
    assert check_states(times, *views) == _scan(times, *views) == 2
    sums.clear()
    part = np.concatenate([one, one]).copy()  # views of an array larger than them
    larger = [part[a:b].reshape(rows, -1) for a, b in zip(edges[:-1], edges[1:],
                                                         strict=True)]
    part[-1] = np.nan  # outside the views: not theirs
    assert check_states(times, *larger) == _scan(times, *larger) and len(sums) == 5
