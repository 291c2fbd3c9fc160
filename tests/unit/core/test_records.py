"""core.records.record against the dataclass it replaces: the same repr, equality, hash,
replace(), immutability and field options, class by class."""

import dataclasses
import inspect
import pickle
from dataclasses import dataclass, field

import numpy as np
import pytest

from casmech.core.records import record


@record
class Pickled:
    a: float
    b: tuple = ()


def _pair(frozen: bool = True, **options):
    """The same class body as a dataclass and as a record."""

    def body():
        class Point:
            __annotations__ = {"x": "float", "y": "float", "tags": "tuple",
                               "note": "str", "cached": "int"}
            x: float
            y: float = 2.0
            tags: tuple = field(default_factory=tuple)
            note: str = field(default="", compare=False, repr=False)
            cached: int = field(default=0, hash=False)

        return Point

    return (dataclass(frozen=frozen, **options)(body()),
            record(frozen=frozen, **options)(body()))


@pytest.mark.parametrize("frozen", [True, False])
def test_repr_eq_hash_as_a_dataclass(frozen):
    made, rec = _pair(frozen)
    for args in [(1.0,), (1.0, 3.0, (1, 2), "a", 4), (np.float64(2.5), -1.0)]:
        a, b = made(*args), rec(*args)
        assert repr(a) == repr(b)
        assert (a == made(*args)) is (b == rec(*args)) is True
        assert (a == made(9.0)) is (b == rec(9.0)) is False
        assert b.__eq__(a) is NotImplemented  # another class: never equal
        if frozen:
            assert hash(a) == hash(b)
        else:
            assert made.__hash__ is None and rec.__hash__ is None
    # compare=False: a field left out of equality (and of the hash) in both
    assert rec(1.0, note="a") == rec(1.0, note="b")
    assert made(1.0, note="a") == made(1.0, note="b")
    assert dataclasses.replace(rec(1.0), y=5.0) == rec(1.0, 5.0)
    assert [f.name for f in dataclasses.fields(rec)] == [f.name for f in dataclasses.fields(made)]
    assert dataclasses.asdict(rec(1.0)) == dataclasses.asdict(made(1.0))


def test_frozen_fields_are_written_once():
    _, rec = _pair()
    value = rec(1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        value.x = 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        value.other = 2.0  # not a field either
    with pytest.raises(dataclasses.FrozenInstanceError):
        del value.x
    object.__setattr__(value, "cached", 3)  # what a __post_init__ may do, as with a dataclass
    assert value.cached == 3
    kept = Pickled(1.0, (2, 3))
    assert pickle.loads(pickle.dumps(kept)) == kept  # unpickling writes __dict__, not fields


def test_mutable_record_assigns():
    _, rec = _pair(frozen=False)
    value = rec(1.0)
    value.x = 4.0
    assert value == rec(4.0)


def test_own_methods_and_eq_false_are_kept():
    @record(eq=False)
    class Identity:
        a: int

    one = Identity(1)
    assert one == one and Identity(1) != Identity(1)

    @record
    class Own:
        a: int

        def __eq__(self, other):
            return True

        __hash__ = object.__hash__

        def __repr__(self):
            return "own"

    assert Own(1) == Own(2) and repr(Own(1)) == "own"

    @record
    class Base:
        a: int

    @record
    class Child(Base):
        b: int = 0

    assert Child(1, 2) != Base(1) and Child(1, 2) == Child(1, 2)
    assert repr(Child(1, 2)) == "test_own_methods_and_eq_false_are_kept.<locals>.Child(a=1, b=2)"
    assert hash(Child(1, 2)) == hash((1, 2))


def test_a_frozen_dataclass_extends_a_record():
    """What a formulation written by a user does (docs/architecture.md): a frozen dataclass
    over a frozen record, and a record over that."""

    @record
    class Base:
        a: float = 1.0

    @dataclass(frozen=True)
    class User(Base):
        b: float = 2.0

    @record
    class Again(User):
        c: float = 3.0

    assert User(1.0, 2.0) == User(1.0, 2.0) and hash(User()) == hash((1.0, 2.0))
    assert repr(Again()).endswith("Again(a=1.0, b=2.0, c=3.0)")
    for value in (User(), Again()):
        with pytest.raises(dataclasses.FrozenInstanceError):
            value.a = 5.0
    with pytest.raises(TypeError, match="non-frozen"):  # as for a frozen dataclass
        dataclass(type("Mutable", (Base,), {"__annotations__": {"d": "int"}, "d": 0}))


def test_a_frozen_records_init_is_a_frozen_dataclasss():
    """The same signature, defaults, default factories (a new object each time) and
    __post_init__; a field after a defaulted one refused as dataclasses refuse it."""
    made, rec = _pair()
    assert str(inspect.signature(rec)) == str(inspect.signature(made))
    assert rec.__doc__ == made.__doc__  # (undocumented: the name and signature)

    @record
    class Later:
        a: list = field(default_factory=list)
        b: int = field(default=4, init=False)
        c: dict = field(default_factory=dict, init=False)

        def __post_init__(self):
            object.__setattr__(self, "b", len(self.a))

    one, two = Later(), Later([1, 2])
    assert (one.a, one.b, one.c, two.a, two.b) == ([], 0, {}, [1, 2], 2)
    assert one.a is not Later().a and one.c is not Later().c
    with pytest.raises(TypeError, match="'b' follows default argument"):
        record(type("Wrong", (), {"__annotations__": {"a": "int", "b": "int"}, "a": 0,
                                  "__module__": __name__}))


def test_a_frozen_records_init_is_compiled_when_first_called():
    """Until the class is first called its __init__ has the compiled one's signature, names
    and annotations; the first call compiles it into the class's own place (once: the second
    call runs it), and the instances are those of the same dataclass."""
    made, rec = _pair()
    waiting = rec.__dict__["__init__"]
    assert str(inspect.signature(rec)) == str(inspect.signature(made))
    assert (waiting.__qualname__, waiting.__annotations__) == \
        (made.__init__.__qualname__, made.__init__.__annotations__)
    first = rec(1.0, tags=(1,))
    compiled = rec.__dict__["__init__"]
    assert compiled is not waiting and compiled.__code__.co_varnames[0] == "__record_self__"
    assert str(inspect.signature(compiled)) == str(inspect.signature(waiting))
    assert (compiled.__qualname__, compiled.__annotations__) == \
        (waiting.__qualname__, waiting.__annotations__)
    second = rec(1.0, tags=(1,))
    assert rec.__dict__["__init__"] is compiled
    assert first == second and repr(first) == repr(made(1.0, tags=(1,))).replace(
        made.__qualname__, rec.__qualname__)
    with pytest.raises(TypeError, match="missing 1 required positional argument: 'x'"):
        _pair()[1]()  # (the first call's arguments reach the compiled __init__)


def test_a_record_with_an_init_only_field_keeps_dataclasses_init():
    @record
    class Scaled:
        a: float
        scale: dataclasses.InitVar[float] = 1.0

        def __post_init__(self, scale):
            object.__setattr__(self, "a", self.a * scale)

    assert Scaled(2.0, 3.0).a == 6.0 and Scaled(2.0).a == 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        Scaled(1.0).a = 2.0


@pytest.mark.parametrize("annotations", [{}, {"a": "int"}, {"a": "int", "b": "int"}])
def test_eq_and_hash_of_any_number_of_fields_as_a_dataclass(annotations):
    """Zero and one compared field too (their getters are lambdas, not attrgetters)."""
    def body():
        return type("Few", (), {"__annotations__": dict(annotations), "__module__": __name__})

    made, rec = dataclass(frozen=True)(body()), record(body())
    args = range(len(annotations))
    assert (rec(*args) == rec(*args)) is (made(*args) == made(*args)) is True
    assert hash(rec(*args)) == hash(made(*args))
    if annotations:
        assert (rec(*args) == rec(*[9] * len(annotations))) is False


@pytest.mark.parametrize("init", [True, False])
def test_a_frozen_records_dataclass_parameters_are_a_frozen_dataclasss(init):
    """dataclasses reads a frozen record's parameters (every slot) as those of a frozen
    dataclass whose eq and repr are the record's own, each class with a copy of its own."""
    made = _pair(frozen=True, init=init)[1]
    plain = _pair(frozen=True, init=init, eq=False, repr=False)[0]
    ours, theirs = made.__dataclass_params__, plain.__dataclass_params__
    assert type(ours) is type(theirs)
    assert {name: getattr(ours, name) for name in type(ours).__slots__} == \
        {name: getattr(theirs, name) for name in type(theirs).__slots__}
    assert _pair(frozen=True, init=init)[1].__dataclass_params__ is not ours


@pytest.mark.parametrize("frozen", [True, False])
def test_a_records_own_init_is_compiled_when_first_called_mutable_or_over_a_frozen_base(
        frozen):
    """A mutable record, and a record over a frozen record, get the record's own __init__
    (compiled when first called), with the dataclass's signature, doc and instances; the
    mutable one assigns through the class's own __setattr__, as a dataclass's __init__ does."""
    made, rec = _pair(frozen=frozen)
    assert rec.__dict__["__init__"].__code__.co_varnames[0] == "__record_self__"
    assert str(inspect.signature(rec)) == str(inspect.signature(made))
    assert rec.__doc__ == made.__doc__
    assert repr(rec(1.0, tags=(1,))) == repr(made(1.0, tags=(1,))).replace(
        made.__qualname__, rec.__qualname__)
    if not frozen:
        seen = []

        @record(frozen=False)
        class Watched:
            a: int
            b: list = field(default_factory=list)

            def __setattr__(self, name, value):
                seen.append(name)
                object.__setattr__(self, name, value)

        assert Watched(1).b == [] and seen == ["a", "b"]
        return

    @record
    class Base:
        a: float = 1.0

    @record
    class Over(Base):
        b: float = 2.0

    @dataclass(frozen=True)
    class OverDataclass(Base):
        b: float = 2.0

    assert Over.__dict__["__init__"].__code__.co_varnames[0] == "__record_self__"
    assert str(inspect.signature(Over)) == str(inspect.signature(OverDataclass))
    assert (Over(3.0).a, Over(3.0, 4.0).b, Over() == Over(), hash(Over())) == \
        (3.0, 4.0, True, hash((1.0, 2.0)))
    with pytest.raises(dataclasses.FrozenInstanceError):
        Over().b = 5.0
