"""`record`: a dataclass whose methods other than __init__ are shared functions over the class's
field names, instead of methods compiled from generated source for every class.

The standard decorator compiles each generated method with exec (six for a frozen class),
so each class costs a compilation per method when a module is imported (measurements:
benchmarks/RESULTS.md, "Whole processes, both commits"). A record compiles only its __init__ and
behaves as the dataclass it replaces: the same fields, __init__, replace(), fields() and
asdict(), the same repr, equality (same class, equal tuples of the compared fields) and hash
(of the hashed fields' tuple). A frozen record's fields are written once, by __init__ (or by
object.__setattr__ in __post_init__, as in a frozen dataclass); any later assignment or
deletion raises dataclasses.FrozenInstanceError."""

from __future__ import annotations

import copy
import dataclasses
import reprlib
from operator import attrgetter


def record(cls=None, /, *, frozen: bool = True, eq: bool = True, repr: bool = True,  # noqa: A002
           **options):
    """As `dataclasses.dataclass(frozen=frozen, eq=eq, repr=repr, **options)`, frozen by
    default; `order` and `unsafe_hash` are not taken (use dataclass for those)."""

    def wrap(cls):
        # a frozen base (a record or a dataclass) needs dataclasses' own frozen subclass
        made = dataclasses.dataclass(cls, eq=False, repr=False, frozen=frozen and _frozen_base(cls),
                                     **options)
        if frozen:  # to dataclasses a frozen record is frozen: a frozen dataclass may extend it
            params = copy.copy(made.__dataclass_params__)
            params.frozen = True
            made.__dataclass_params__ = params
        _share(made, eq, repr, frozen)
        return made

    return wrap if cls is None else wrap(cls)


def _frozen_base(cls) -> bool:
    return any(dataclasses.is_dataclass(base) and base.__dataclass_params__.frozen
               for base in cls.__mro__[1:])


def _getter(names: tuple[str, ...]):
    """object -> the tuple of its attributes `names` (attrgetter returns a bare value for one)."""
    if len(names) == 1:
        one = attrgetter(names[0])
        return lambda value: (one(value),)
    return attrgetter(*names) if names else lambda value: ()


def _share(cls, eq: bool, with_repr: bool, frozen: bool) -> None:
    fields = dataclasses.fields(cls)
    own = cls.__dict__
    if frozen:
        cls.__record_fields__ = frozenset(f.name for f in fields)
        cls.__setattr__, cls.__delattr__ = _write_once, _no_delete
    if with_repr and "__repr__" not in own:
        cls.__record_repr__ = tuple(f.name for f in fields if f.repr)
        cls.__repr__ = _repr
    if not eq:
        return
    if "__eq__" not in own:
        cls.__record_compare__ = _getter(tuple(f.name for f in fields if f.compare))
        cls.__eq__ = _eq
    # dataclasses' rule: eq and frozen give a hash of the compared fields unless the class
    # wrote its own; eq alone makes instances unhashable
    explicit = own.get("__hash__", dataclasses.MISSING)
    if explicit is dataclasses.MISSING or (explicit is None and "__eq__" in own):
        if frozen:
            hashed = tuple(f.name for f in fields if (f.compare if f.hash is None else f.hash))
            cls.__record_hash__ = _getter(hashed)
            cls.__hash__ = _hash
        else:
            cls.__hash__ = None


def _write_once(self, name: str, value) -> None:
    if name in self.__dict__ or name not in self.__record_fields__:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")
    object.__setattr__(self, name, value)


def _no_delete(self, name: str) -> None:
    raise dataclasses.FrozenInstanceError(f"cannot delete field {name!r}")


@reprlib.recursive_repr()
def _repr(self) -> str:
    values = ", ".join(f"{name}={getattr(self, name)!r}" for name in self.__record_repr__)
    return f"{type(self).__qualname__}({values})"


def _eq(self, other):
    if other.__class__ is self.__class__:
        compare = self.__record_compare__
        return compare(self) == compare(other)
    return NotImplemented


def _hash(self) -> int:
    return hash(self.__record_hash__(self))
