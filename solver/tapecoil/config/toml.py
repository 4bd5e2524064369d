"""The configuration as TOML: read, checked (:class:`ConfigError` naming the key) and written back."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Any, get_type_hints

from tapecoil.config.params import ConfigError, coerce
from tapecoil.config.sections import Config

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10 (conda environments)
    import tomli as tomllib


ISOTROPIC_KEYS = ("E", "nu")
"""The [tape] keys of an isotropic wall, which a laminate replaces."""


def config_from_dict(data: dict[str, Any]) -> Config:
    """Build and validate a :class:`Config` from a nested mapping (parsed TOML)."""
    sections = {f.name: f for f in dataclasses.fields(Config)}
    kwargs = {}
    for name, table in data.items():
        if name not in sections:
            raise ConfigError(f"unknown section [{name}] (known: {', '.join(sections)})")
        if not isinstance(table, dict):
            raise ConfigError(f"[{name}] must be a table of keys")
        cls = sections[name].default_factory
        hints = get_type_hints(cls)
        known = {f.name for f in dataclasses.fields(cls)}
        for key, value in table.items():
            if key not in known:
                raise ConfigError(f"unknown key {name}.{key} (known in [{name}]: {', '.join(sorted(known))})")
            table[key] = coerce(f"{name}.{key}", hints[key], value)
        kwargs[name] = cls(**table)
    laminate = kwargs.get("laminate")
    if laminate is not None and laminate.kind != "isotropic":
        for key in ISOTROPIC_KEYS:
            if key in data.get("tape", {}):
                raise ConfigError(
                    f"tape.{key} does not act with a laminate (laminate.kind = {laminate.kind!r}): the "
                    f"wall's stiffness comes from [laminate]; leave tape.{key} out"
                )
    config = Config(**kwargs)
    config.check()
    return config


def load_config(path: str | Path | None = None) -> Config:
    """Read a TOML file (or the defaults when ``path`` is None) and validate it."""
    if path is None:
        config = Config()
        config.check()
        return config
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except FileNotFoundError:
        raise ConfigError(f"configuration file not found: {path}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path} is not valid TOML: {exc}") from None
    return config_from_dict(data)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return str(v)


def to_toml(config: Config) -> str:
    """The configuration as TOML, with units as comments; ``load_config`` reads it back."""
    lines = []
    for sec in dataclasses.fields(config):
        section = getattr(config, sec.name)
        lines.append(f"[{sec.name}]")
        for f in dataclasses.fields(section):
            if sec.name == "tape" and f.name in ISOTROPIC_KEYS and config.laminate.kind != "isotropic":
                continue
            v = getattr(section, f.name)
            if isinstance(v, dict):
                inner = ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items())
                lines.append(f"{f.name} = {{{inner}}}")
                continue
            unit = f.metadata.get("unit", "")
            lines.append(f"{f.name} = {_toml_value(v)}" + (f"  # [{unit}]" if unit and unit != "-" else ""))
        lines.append("")
    return "\n".join(lines)
