"""A scene written back as a scene file: every setting, its default filled in, with what it means.

``simatch scenes NAME --toml > my.toml`` writes one, to be edited and run (``simatch run my.toml``): the same
scene, seed and settings give the same run. Each key gets a comment from its field's description and limits
(and the choices where a key takes one of a few words). Plug-ins (the robot model, the strategy, the judge)
check their own parameters with their own pydantic models: given those models (`PluginParams`), their tables
are filled in and commented the same way; without, what the scene says is written as it is.

TOML has no null: a setting that is not set (a default of None, e.g. ``duration``) is written as a comment
that says so.
"""

from __future__ import annotations

import textwrap
import typing
from collections.abc import Mapping
from typing import Any

import annotated_types as at
import tomlkit
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from tomlkit.items import Array, InlineTable, Table

from ..worlds import world_class
from .loader import LoadedScene, validate_params

#: table (dotted, e.g. "teams.cyan.strategy_params" or "judge") -> the plug-in's parameter model
PluginParams = Mapping[str, type[BaseModel] | None]

WIDTH = 100
#: the tables of plug-ins' own settings (the robot model's, the strategy's, the world's)
PLUGIN_TABLES = ("model_params", "strategy_params", "world.params")
_LEFT_OUT = object()
_LIMITS = ((at.Gt, ">", "gt"), (at.Ge, ">=", "ge"), (at.Lt, "<", "lt"), (at.Le, "<=", "le"))


def scene_toml(loaded: LoadedScene, plugins: PluginParams | None = None, header: str = "") -> str:
    """The scene as TOML text that loads back to the same scene (`load_scene` on it gives an equal spec)."""
    plugins = dict(plugins or {})
    spec = loaded.spec
    doc = tomlkit.document()
    for paragraph in header.splitlines():
        for line in _wrap(paragraph) or [""]:
            doc.add(tomlkit.comment(line) if line else tomlkit.nl())
    if header:
        doc.add(tomlkit.nl())
    # the world's kind decides some of its keys: it refuses another kind's (a soccer field's lines are no
    # setting of an arena), and a key it is not given may default to its own value rather than the schema's
    world = world_class(spec.world.kind)
    kind_keys = {f"world.{key}": _LEFT_OUT for key in world.foreign_keys}
    kind_keys |= {f"world.{key}": value for key, value in world.own_defaults.items()}
    _fill(doc, spec, type(spec), "", plugins, loaded.source, kind_keys)
    return tomlkit.dumps(doc)


def _fill(
    table, model: BaseModel, cls: type[BaseModel], path: str, plugins: dict, source: str, kind_keys: dict
) -> None:
    """Keys first, then sub-tables (TOML puts a table's own keys before its sub-tables). ``kind_keys``: keys
    left out (`_LEFT_OUT`) or, when the scene does not set them, written with another default."""
    later: list[tuple[str, Any]] = []
    for name, info in cls.model_fields.items():
        value = getattr(model, name)
        where = f"{path}.{name}" if path else name
        if where in kind_keys:
            if kind_keys[where] is _LEFT_OUT:
                continue
            if name not in model.model_fields_set:
                value = kind_keys[where]
        if isinstance(value, BaseModel) or _is_table_of_models(value):
            later.append((name, value))
            continue
        if where.endswith(PLUGIN_TABLES) and isinstance(value, dict):
            later.append((name, value))
            continue
        _key(table, name, value, info, where)
    extra = getattr(model, "model_extra", None) or {}
    if path in plugins or extra:  # a plug-in's own settings beside the known keys (the judge's)
        _plugin_keys(table, extra, plugins.get(path), path, source)
    for name, value in later:
        where = f"{path}.{name}" if path else name
        info = cls.model_fields[name]
        if isinstance(value, BaseModel):
            sub = _table(info)
            _fill(sub, value, type(value), where, plugins, source, kind_keys)
            table.add(name, sub)
        elif isinstance(value, dict) and value and all(isinstance(v, BaseModel) for v in value.values()):
            outer = _table(info, super_table=True)
            for key, item in value.items():
                sub = tomlkit.table()
                _fill(sub, item, type(item), f"{where}.{key}", plugins, source, kind_keys)
                outer.add(key, sub)
            table.add(name, outer)
        else:  # a plug-in's parameter table: model_params, strategy_params, the world's params
            params = plugins.get(where)
            if params is None and not value:
                continue
            sub = tomlkit.table()
            kind = "kind" if name == "params" else name.removesuffix("_params")
            what = {"model": "robot model", "kind": "world"}.get(kind, kind)
            if params is not None and not params.model_fields and not value:
                sub.add(tomlkit.comment(f"the {what} {getattr(model, kind, '')!r} has no settings of its own"))
            else:
                sub.add(tomlkit.comment(f"the settings of the {what} {getattr(model, kind, '')!r}"))
            _plugin_keys(sub, value, params, where, source)
            table.add(name, sub)


def _is_table_of_models(value: Any) -> bool:
    return isinstance(value, dict) and bool(value) and all(isinstance(v, BaseModel) for v in value.values())


def _table(info: FieldInfo, super_table: bool = False) -> Table:
    table = tomlkit.table(is_super_table=super_table)
    model = info.annotation if isinstance(info.annotation, type) else None
    about = info.description or (model.__dict__.get("__doc__") if model is not None else None)
    if about and not super_table:
        for line in _wrap(" ".join(about.split())):
            table.add(tomlkit.comment(line))
    return table


def _plugin_keys(table, given: dict, params: type[BaseModel] | None, where: str, source: str) -> None:
    """A plug-in's settings: with its model, every one (defaults filled in, commented); else as the scene has them."""
    if params is None:
        for key, value in given.items():
            table.add(key, _toml_value(value, f"{where}.{key}"))
        return
    checked = validate_params(params, given, source, where)
    for name, info in type(checked).model_fields.items():
        _key(table, name, getattr(checked, name), info, f"{where}.{name}")


def _key(table, name: str, value: Any, info: FieldInfo, where: str) -> None:
    note = _note(info)
    if value is None:
        if info.default is not None and not info.is_required():
            raise ValueError(f"{where}: None cannot be written in TOML and is not the default")
        for line in _wrap(f"{name} is not set" + (f": {note}" if note else "")):
            table.add(tomlkit.comment(line))
        return
    for line in _wrap(note):
        table.add(tomlkit.comment(line))
    table.add(name, _toml_value(value, where))


def _note(info: FieldInfo) -> str:
    """What a field means and what it takes: its description, its limits, its choices."""
    parts = [info.description] if info.description else []
    limits = []
    for meta in info.metadata:
        for kind, sign, attr in _LIMITS:
            if isinstance(meta, kind):
                limits.append(f"{sign} {getattr(meta, attr)}")
        if isinstance(meta, at.MinLen) and meta.min_length > 1:
            limits.append(f"at least {meta.min_length} items")
        if isinstance(meta, at.MaxLen):
            limits.append(f"at most {meta.max_length} items")
    choices = _choices(info.annotation)
    if choices:
        limits.append("one of " + ", ".join(f'"{c}"' if isinstance(c, str) else repr(c) for c in choices))
    if limits:
        parts.append(f"({', '.join(limits)})")
    return " ".join(parts)


def _choices(annotation) -> list:
    if typing.get_origin(annotation) is typing.Literal:
        return list(typing.get_args(annotation))
    out = []
    for arg in typing.get_args(annotation) or ():
        out += _choices(arg)
    return out


def _wrap(text: str) -> list[str]:
    """Comment lines of at most WIDTH characters; a limit such as "<= 0.02" is never split (a no-break space
    holds it together while wrapping); docstring markup becomes plain quotes."""
    text = text.replace("``", "'")
    for sign in ("<=", ">=", "<", ">"):
        text = text.replace(f"{sign} ", f"{sign}\u00a0")
    return [line.replace("\u00a0", " ") for line in textwrap.wrap(text, WIDTH - 2, break_on_hyphens=False)]


def _toml_value(value: Any, where: str):
    """A TOML item for a settings value: scalars as they are, lists (multi-line when long), tables inline."""
    if isinstance(value, BaseModel):
        value = value.model_dump()
    if isinstance(value, dict):
        inline: InlineTable = tomlkit.inline_table()
        for k, v in value.items():
            if v is not None:
                inline.append(str(k), _toml_value(v, f"{where}.{k}"))
        return inline
    if isinstance(value, (list, tuple)):
        array: Array = tomlkit.array()
        for v in value:
            array.append(_toml_value(v, where))
        if len(value) > 1 and all(isinstance(v, (list, tuple, dict, BaseModel)) for v in value):
            array.multiline(True)
        return array
    if value is None:
        raise ValueError(f"{where}: None cannot be written in TOML")
    if isinstance(value, (bool, int, float, str)):
        return tomlkit.item(value)
    raise ValueError(f"{where}: {type(value).__name__} cannot be written in TOML")
