"""`record`: a dataclass whose methods other than __init__ are shared functions over the class's
field names, instead of methods compiled from generated source for every class.

The standard decorator compiles each generated method with exec (six for a frozen class),
so each class costs a compilation per method when a module is imported (measurements:
benchmarks/RESULTS.md, "Whole processes, both commits"). A record compiles only its __init__,
when the class is first called (a process calls some of the classes it imports), and
behaves as the dataclass it replaces: the same fields, __init__, replace(), fields() and
asdict(), the same repr, equality (same class, equal tuples of the compared fields) and hash
(of the hashed fields' tuple). A frozen record's fields are written once, by __init__ (or by
object.__setattr__ in __post_init__, as in a frozen dataclass); any later assignment or
deletion raises dataclasses.FrozenInstanceError. Its __init__ writes each field by
object.__setattr__, as a frozen dataclass's does, rather than through the class's own
__setattr__ (a Python call per field of every instance; docs/decisions/frozen-records.md).
A mutable record's __init__ assigns each field, as a dataclass's does; a record extending a
frozen class is made frozen by dataclasses (its own __setattr__ and __delattr__, replaced by
the shared ones) but gets the record's own __init__ too.
"""

from __future__ import annotations

import dataclasses
import inspect
import reprlib
from operator import attrgetter


def record(cls=None, /, *, frozen: bool = True, eq: bool = True, repr: bool = True,  # noqa: A002
           **options):
    """As `dataclasses.dataclass(frozen=frozen, eq=eq, repr=repr, **options)`, frozen by
    default; `order` and `unsafe_hash` are not taken (use dataclass for those)."""

    def wrap(cls):
        # a frozen base (a record or a dataclass) needs dataclasses' own frozen subclass
        base = frozen and _frozen_base(cls)
        init = options.get("init", True)
        own_init = init and _plain_fields(cls, options)
        given = {key: value for key, value in options.items() if key != "init"}
        undocumented = own_init and not cls.__doc__
        if undocumented:  # (dataclasses would read it from __init__, not written yet)
            cls.__doc__ = "-"
        made = dataclasses.dataclass(cls, eq=False, repr=False, frozen=base,
                                     init=init and not own_init, **given)
        if own_init:
            made.__init__ = _own_init(made, frozen)
        if undocumented:  # dataclasses' own: the class's name and signature
            made.__doc__ = f"{made.__name__}{inspect.signature(made)}".replace(" -> None", "")
        if frozen:  # to dataclasses a frozen record is frozen: a frozen dataclass may extend it
            params = _copied(made.__dataclass_params__)
            params.frozen, params.init = True, init
            made.__dataclass_params__ = params
        _share(made, eq, repr, frozen)
        return made

    return wrap if cls is None else wrap(cls)


def _copied(params):
    """A copy of a class's dataclass parameters, slot by slot (copy.copy's reduce protocol
    costs several times more, once per record class a process makes)."""
    kind = type(params)
    made = object.__new__(kind)
    for name in kind.__slots__:
        object.__setattr__(made, name, getattr(params, name))
    return made


def _frozen_base(cls) -> bool:
    return any(dataclasses.is_dataclass(base) and base.__dataclass_params__.frozen
               for base in cls.__mro__[1:])


def _plain_fields(cls, options: dict) -> bool:
    """Whether the class's fields are all plain (no InitVar, ClassVar or keyword-only field, no
    slots), which `_own_init` writes; others keep dataclasses' __init__."""
    if options.get("kw_only") or options.get("slots"):
        return False
    written = cls.__dict__.get("__annotations__", {}).values()
    if any(kind in str(annotation) for annotation in written
           for kind in ("InitVar", "ClassVar", "KW_ONLY")):
        return False
    for base in cls.__mro__[1:]:
        if dataclasses.is_dataclass(base) and (
                len(base.__dataclass_fields__) != len(dataclasses.fields(base))
                or any(f.kw_only for f in dataclasses.fields(base))):
            return False
    return True


class _Factory:
    """The default of a parameter whose field has a default_factory."""

    def __repr__(self) -> str:
        return "<factory>"


_FACTORY = _Factory()


def _own_init(cls, frozen: bool):
    """The __init__ dataclasses writes for a class of these fields: the parameters in field
    order (defaults and default factories as there), each field set (frozen: by
    object.__setattr__; else by assignment), then __post_init__ when the class has one. Its
    text is compiled when the class is first called (`_compiled_on_first_call`); until then
    the class's __init__ has that function's signature, annotations and names."""
    names = {"__record_set__": object.__setattr__, "__record_factory__": _FACTORY}
    parameters, lines, defaulted = ["__record_self__"], [], False
    signature = [inspect.Parameter("__record_self__", _POSITIONAL)]
    for f in dataclasses.fields(cls):
        factory = f.default_factory is not dataclasses.MISSING
        if f.init:
            if f.default is not dataclasses.MISSING:
                names[f"__default_{f.name}"] = f.default
                parameters.append(f"{f.name}=__default_{f.name}")
            elif factory:
                parameters.append(f"{f.name}=__record_factory__")
            elif defaulted:
                raise TypeError(f"non-default argument {f.name!r} follows default argument")
            else:
                parameters.append(f.name)
            defaulted = defaulted or factory or f.default is not dataclasses.MISSING
            value = (f"__factory_{f.name}() if {f.name} is __record_factory__ else {f.name}"
                     if factory else f.name)
            default = _FACTORY if factory else f.default
            signature.append(inspect.Parameter(
                f.name, _POSITIONAL, annotation=f.type,
                default=inspect.Parameter.empty if default is dataclasses.MISSING else default))
        elif factory:
            value = f"__factory_{f.name}()"
        else:
            continue  # (a default of a field left out of __init__ is the class's attribute)
        if factory:
            names[f"__factory_{f.name}"] = f.default_factory
        lines.append(f"    __record_set__(__record_self__, {f.name!r}, {value})" if frozen
                     else f"    __record_self__.{f.name} = {value}")
    if hasattr(cls, "__post_init__"):
        lines.append("    __record_self__.__post_init__()")
    text = f"def __init__({', '.join(parameters)}):\n" + ("\n".join(lines) or "    pass")
    annotations = {f.name: f.type for f in dataclasses.fields(cls) if f.init}
    annotations["return"] = None
    first = _compiled_on_first_call(cls, text, names, annotations)
    first.__signature__ = inspect.Signature(signature, return_annotation=None)
    return first


_POSITIONAL = inspect.Parameter.POSITIONAL_OR_KEYWORD


def _named(function, cls, annotations: dict):
    """`function` named as the __init__ of `cls`."""
    function.__qualname__ = f"{cls.__qualname__}.__init__"
    function.__module__ = cls.__module__
    function.__annotations__ = dict(annotations)
    return function


def _compiled_on_first_call(cls, text: str, names: dict, annotations: dict):
    """An __init__ that compiles `text` (a record's __init__), puts it in its own place in
    `cls` and calls it: a module's records are made at import, and a process calls some of
    them only."""

    def __init__(__record_self__, *args, **kwargs):  # noqa: N807
        exec(text, names)  # noqa: S102 (the text is made of the class's own field names)
        function = _named(names["__init__"], cls, annotations)
        if cls.__dict__.get("__init__") is __init__:
            cls.__init__ = function
        function(__record_self__, *args, **kwargs)

    return _named(__init__, cls, annotations)


def _getter(names: tuple[str, ...]):
    """object -> the tuple of its attributes `names` (attrgetter returns a bare value for one;
    a class keeps it as a staticmethod, so that a lambda is not bound to the instance)."""
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
        cls.__record_compare__ = staticmethod(_getter(tuple(f.name for f in fields
                                                             if f.compare)))
        cls.__eq__ = _eq
    # dataclasses' rule: eq and frozen give a hash of the compared fields unless the class
    # wrote its own; eq alone makes instances unhashable
    explicit = own.get("__hash__", dataclasses.MISSING)
    if explicit is dataclasses.MISSING or (explicit is None and "__eq__" in own):
        if frozen:
            hashed = tuple(f.name for f in fields if (f.compare if f.hash is None else f.hash))
            cls.__record_hash__ = staticmethod(_getter(hashed))
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
