"""core.last_call: the value for the arguments given last, compared by identity."""

from casmech.core.last_call import last_call


def test_the_last_arguments_are_answered_without_computing_again():
    calls = []
    square = last_call(lambda x: calls.append(x) or [x * x])
    a, b = 3.5, 4.5
    first = square(a)
    assert square(a) is first and calls == [a]
    assert square(b) == [b * b] and calls == [a, b]
    assert square(a) == [a * a] and calls == [a, b, a]  # only the last is kept


def test_arguments_are_compared_by_identity_not_value():
    calls = []
    keyed = last_call(lambda *items: calls.append(items) or len(calls))
    one, other = [1, 2], [1, 2]  # equal, not the same object
    assert keyed(one, "x") == 1
    assert keyed(other, "x") == 2
    assert keyed(other, "x") == 2 and len(calls) == 2
