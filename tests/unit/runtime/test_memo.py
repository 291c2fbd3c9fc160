"""runtime.memo.kept: built once per key, the oldest entry dropped at the limit."""

from casmech.runtime.memo import kept


def test_built_once_and_bounded():
    store, builds = {}, []

    def build(key):
        return lambda: builds.append(key) or key * 10

    assert [kept(store, k, build(k), 2) for k in (1, 2, 1)] == [10, 20, 10]
    assert builds == [1, 2]  # the second 1 was kept
    assert kept(store, 3, build(3), 2) == 30
    assert list(store) == [2, 3]  # 1, the oldest, went
