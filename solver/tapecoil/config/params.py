"""The parameter machinery: a field with its unit and allowed values, and the checks of a value.

Every section of :mod:`tapecoil.config.sections` is made of :func:`param` fields, so that one
check (:func:`check_section`) and one type test (:func:`coerce`) serve them all and every error
names its key and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, get_type_hints


class ConfigError(ValueError):
    """A configuration value that cannot be used; the message names the key and the range."""


class ConfigWarning(UserWarning):
    """A configuration that can be run but is unlikely to give what it asks for; names the key."""


@dataclass(frozen=True)
class Range:
    """Allowed interval of a numeric parameter; open or closed at each end."""

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False

    def contains(self, x: float) -> bool:
        above = x > self.lo if self.lo_open else x >= self.lo
        below = x < self.hi if self.hi_open else x <= self.hi
        return above and below

    def describe(self) -> str:
        if self.hi == math.inf:
            return f"{'>' if self.lo_open else '>='} {self.lo:g}"
        if self.lo == -math.inf:
            return f"{'<' if self.hi_open else '<='} {self.hi:g}"
        return f"in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}{')' if self.hi_open else ']'}"


POSITIVE = Range(0.0, lo_open=True)
NON_NEGATIVE = Range(0.0)


def param(default: Any, unit: str = "", allowed: Range | tuple[str, ...] | None = None, **kw):
    """A dataclass field with its unit and allowed values recorded for validation and docs."""
    if isinstance(default, (dict, list)):
        return field(
            default_factory=lambda: type(default)(default), metadata={"unit": unit, "allowed": allowed}, **kw
        )
    return field(default=default, metadata={"unit": unit, "allowed": allowed}, **kw)


def _type_name(tp: Any) -> str:
    return {
        float: "a number",
        int: "an integer",
        bool: "true or false",
        str: "a string",
        dict: "a table",
        list: "a list of numbers",
    }.get(tp, str(tp))


def coerce(key: str, tp: Any, value: Any) -> Any:
    """Check a TOML value against the field type; ints are accepted where floats are."""
    ok = (
        (tp is float and isinstance(value, (int, float)) and not isinstance(value, bool))
        or (tp is int and isinstance(value, int) and not isinstance(value, bool))
        or (tp is bool and isinstance(value, bool))
        or (tp is str and isinstance(value, str))
        or (tp is dict and isinstance(value, dict))
        or (
            tp is list
            and isinstance(value, list)
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        )
    )
    if not ok:
        raise ConfigError(f"{key} must be {_type_name(tp)} (got {type(value).__name__} {value!r})")
    if tp is float:
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{key} must be a finite number (got {value!r})")
    if tp is list:
        value = [float(v) for v in value]
        if not all(math.isfinite(v) for v in value):
            raise ConfigError(f"{key} must hold finite numbers (got {value!r})")
    if tp is dict:
        for k, v in value.items():
            if not isinstance(v, (str, int, float, bool)):
                raise ConfigError(f"{key}.{k} must be a string, number or boolean (got {type(v).__name__})")
    return value


def check_section(name: str, section: Any) -> None:
    """Refuse a field of ``section`` (the TOML table ``name``) of the wrong type or out of its range,
    then whatever the section's own ``check`` refuses."""
    hints = get_type_hints(type(section))
    for f in dataclasses.fields(section):
        key = f"{name}.{f.name}"
        value = coerce(key, hints[f.name], getattr(section, f.name))
        allowed, unit = f.metadata.get("allowed"), f.metadata.get("unit", "")
        if isinstance(allowed, Range) and not allowed.contains(value):
            raise ConfigError(
                f"{key} = {value!r} is out of range: must be {allowed.describe()}{f' [{unit}]' * bool(unit)}"
            )
        if isinstance(allowed, tuple) and value not in allowed:
            raise ConfigError(
                f"{key} = {value!r} is not allowed: must be one of {', '.join(map(repr, allowed))}"
            )
    if hasattr(section, "check"):
        section.check()
