"""pydantic's findings in the words of b2d's errors: the file, the field path and what was expected.

`ValidationError.errors()` gives each finding's location (`("objects", "plate", "mass")`), its kind and
bounds; the model, walked along that location, gives the field's whole range, unit and description, so a
message reads "field 'objects.plate.mass': expected a number in [0.001, 100.0] kg (got 250.0)"."""

from __future__ import annotations

import types
from typing import Annotated, Any, Callable, Union, get_args, get_origin

import annotated_types
import pydantic
from pydantic import BaseModel

from sim.errors import SpecError


def schema_error(exc: pydantic.ValidationError, path, model: type[BaseModel] | None = None, *, prefix: str = "",
                 error: Callable = SpecError) -> SpecError:
    """pydantic's findings as one error: the first builds it, the others follow on their own lines."""
    findings = [_finding(e, model, prefix) for e in exc.errors()]
    err = error(path, *findings[0])
    if len(findings) > 1:
        more = [f"  field '{f}': expected {x}{_got(g)}" for f, x, g in findings[1:]]
        err.args = ("\n".join([str(err), *more]),)
    err.findings = findings
    return err


def _got(value) -> str:
    return f" (got {value!r})" if value is not None else ""


def field_path(loc, prefix: str = "") -> str:
    """("objects", "plate", "parts", 0, "size") -> "objects.plate.parts[0].size"."""
    out = prefix.rstrip(".")
    for part in loc:
        if part == "[key]":       # pydantic's marker of a bad mapping key: the key itself names the field
            continue
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out or "<document>"


def _finding(err: dict, model, prefix: str) -> tuple[str, str, Any]:
    loc, kind, ctx = tuple(err["loc"]), err["type"], err.get("ctx") or {}
    got = err.get("input")
    if kind == "missing":
        return field_path(loc, prefix), "a value (field is missing)", None
    if kind == "extra_forbidden":
        parent = _type_at(model, loc[:-1]) if model else None
        if not _is_model(parent):
            return field_path(loc, prefix), f"no such key (unknown key '{loc[-1]}')", None
        keys = list(parent.model_fields)
        label = getattr(parent, "keys_label", "a key")       # models outside the catalog base say "a key"
        return field_path(loc, prefix), f"{label} from {keys} (unknown key '{loc[-1]}')", None
    expected = _expected(kind, ctx, err["msg"], _field_info(model, loc) if model else None)
    if got is not None and len(repr(got)) > 120:        # a whole block: its type says enough
        expected, got = f"{expected} (got a {type(got).__name__})", None
    return field_path(loc, prefix), expected, got


_TYPE_WORDS = {
    "int_type": "an integer", "int_parsing": "an integer", "int_from_float": "an integer",
    "float_type": "a number", "float_parsing": "a number", "finite_number": "a finite number",
    "bool_type": "true or false", "bool_parsing": "true or false",
    "string_type": "a string", "list_type": "a list", "tuple_type": "a list", "set_type": "a list",
    "dict_type": "a mapping", "model_type": "a mapping", "model_attributes_type": "a mapping",
}
_BOUND_WORDS = {"greater_than": ("gt", ">"), "greater_than_equal": ("ge", ">="),
                "less_than": ("lt", "<"), "less_than_equal": ("le", "<=")}


_NUMBER_ERRORS = ("int_type", "int_parsing", "int_from_float", "float_type", "float_parsing", "finite_number")


def _expected(kind: str, ctx: dict, msg: str, info) -> str:
    described = getattr(info, "description", None)   # a field may say what it holds ("a list of joint names")
    if described and (kind in _TYPE_WORDS or kind in _BOUND_WORDS):
        return described
    range_words = _range_words(info)
    if range_words and (kind in _BOUND_WORDS or kind in _NUMBER_ERRORS):
        return range_words      # a number field's type and range errors say its whole range and unit
    if kind in _TYPE_WORDS:
        return _TYPE_WORDS[kind]
    if kind in _BOUND_WORDS:
        key, op = _BOUND_WORDS[kind]
        return f"a value {op} {ctx.get(key)}"
    if kind == "literal_error":
        return f"one of {ctx.get('expected')}"
    if kind == "enum":
        return f"one of {ctx.get('expected')}"
    if kind in ("too_short", "too_long"):
        lo, hi = _length_bounds(info)
        if lo is not None and lo == hi:
            return f"a list of {lo} items"
        if kind == "too_short":
            return f"at least {ctx.get('min_length')} item(s)"
        return f"at most {ctx.get('max_length')} item(s)"
    if kind == "string_too_short":
        return "a non-empty string"
    if kind in ("value_error", "assertion_error"):
        return msg.split(", ", 1)[1] if msg.startswith(("Value error, ", "Assertion failed, ")) else msg
    return msg[0].lower() + msg[1:] if msg else kind


def _range_words(info) -> str | None:
    """"a number in [0.05, 2.0]", "an integer >= 1", "a number in [0.001, 100.0] kg"; None without bounds."""
    bounds = _bounds(info)
    if not bounds:
        return None
    kind = "an integer" if _unwrap(info.annotation) is int else "a number"
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    unit = f" {extra['unit']}" if extra.get("unit") else ""
    low = [(op, v) for op, v in bounds.items() if op in (">", ">=")]
    high = [(op, v) for op, v in bounds.items() if op in ("<", "<=")]
    if low and high:
        (lo_op, lo), (hi_op, hi) = low[0], high[0]
        return f"{kind} in {'[' if lo_op == '>=' else '('}{lo}, {hi}{']' if hi_op == '<=' else ')'}{unit}"
    op, v = (low or high)[0]
    return f"{kind} {op} {v}{unit}"


def _metadata(info) -> list:
    """The field's constraints, with those of an Annotated type inside Optional (`PositiveNumber | None`)."""
    found = list(getattr(info, "metadata", ()) or ())
    tp = getattr(info, "annotation", None)
    while tp is not None:
        origin = get_origin(tp)
        if origin is Annotated:
            for m in get_args(tp)[1:]:
                found.extend(m.metadata if isinstance(m, pydantic.fields.FieldInfo) else [m])
            tp = get_args(tp)[0]
        elif origin in (Union, types.UnionType):
            args = [a for a in get_args(tp) if a is not type(None)]
            tp = args[0] if len(args) == 1 else None
        else:
            tp = None
    return found


def _bounds(info) -> dict[str, Any]:
    out = {}
    for m in _metadata(info):
        for attr, op in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
            if isinstance(m, getattr(annotated_types, attr.capitalize())):
                out[op] = getattr(m, attr)
    return out


def _length_bounds(info) -> tuple[int | None, int | None]:
    lo = hi = None
    for m in _metadata(info):
        if isinstance(m, annotated_types.MinLen):
            lo = m.min_length
        if isinstance(m, annotated_types.MaxLen):
            hi = m.max_length
    return lo, hi


# ---------------------------------------------------------------- walking a model along an error's loc


def _is_model(tp) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _unwrap(tp):
    """Optional[X] -> X, Annotated[X, ...] -> X."""
    while True:
        origin = get_origin(tp)
        if origin is Annotated:
            tp = get_args(tp)[0]
        elif origin in (Union, types.UnionType):
            args = [a for a in get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


def _step(tp, part):
    """The type one loc element down from `tp`, with its FieldInfo when it is a model field."""
    tp = _unwrap(tp)
    if _is_model(tp):
        info = tp.model_fields.get(part) if isinstance(part, str) else None
        return (info.annotation, info) if info else (None, None)
    origin, args = get_origin(tp), get_args(tp)
    if origin in (list, tuple, set) and isinstance(part, int) and args:
        return args[0], _annotated_info(args[0])
    if origin is dict and len(args) == 2:
        return args[1], _annotated_info(args[1])
    return None, None


def _annotated_info(tp):
    """Metadata of an Annotated list item or mapping value, shaped like a FieldInfo for `_bounds`."""
    if get_origin(tp) is Annotated:
        return pydantic.fields.FieldInfo.from_annotation(tp)
    return None


def _type_at(model, loc):
    tp = model
    for part in loc:
        tp, _ = _step(tp, part)
        if tp is None:
            return None
    return _unwrap(tp)


def _field_info(model, loc):
    tp, info = model, None
    for part in loc:
        tp, info = _step(tp, part)
        if tp is None:
            return None
    return info

