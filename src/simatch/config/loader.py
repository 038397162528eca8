"""Loading scene files: by shipped name or by path, with ``--set KEY=VALUE`` overrides, and refusal of
anything wrong with a message that names the file, the key and what was expected."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from ..plugins import PluginError
from ..robots import model_class
from ..worlds import WorldError
from .schema import Scene


class SceneError(ValueError):
    """A scene that cannot be used; the message says where and why."""


@dataclass
class LoadedScene:
    """A validated scene plus where it came from (kept in recordings so that a run can be reproduced)."""

    spec: Scene
    source: str  # path, or "<shipped>/name.toml"
    text: str  # the file's text as read
    overrides: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.spec.name


def shipped_scenes() -> dict[str, Any]:
    """Names of the scenes shipped with simatch and their resources."""
    folder = resources.files(__package__).joinpath("scenes")
    return {e.name[:-5]: e for e in folder.iterdir() if e.name.endswith(".toml")}


def resolve(name_or_path: str) -> tuple[str, str]:
    """(source, text) of a scene given by shipped name or by file path."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        try:
            return str(path), path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SceneError(f"scene file {path} does not exist") from None
        except (IsADirectoryError, UnicodeDecodeError, PermissionError) as exc:
            raise SceneError(f"scene file {path} cannot be read: {exc}") from None
    shipped = shipped_scenes()
    if name_or_path in shipped:
        return f"<shipped>/{name_or_path}.toml", shipped[name_or_path].read_text(encoding="utf-8")
    raise SceneError(
        f"no scene named {name_or_path!r}: give a path to a .toml file or one of {', '.join(sorted(shipped))}"
    )


def parse_override(item: str) -> tuple[str, Any]:
    """``"a.b=3"`` -> ``("a.b", 3)``. The value is read as a TOML value, else taken as a plain string."""
    key, sep, raw = item.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SceneError(f"override {item!r}: expected KEY=VALUE, e.g. match.half_duration=300")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value


def apply_overrides(data: dict, overrides: Mapping[str, Any], source: str) -> dict:
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node: Any = data
        for i, part in enumerate(parts[:-1]):
            where = ".".join(parts[: i + 1])
            if isinstance(node, list):
                node = _list_item(node, part, dotted, where, source)
                continue
            if part not in node:
                node[part] = {}
            elif not isinstance(node[part], (dict, list)):
                raise SceneError(f"{source}: override {dotted}: {where} is a value, not a table")
            node = node[part]
        last = parts[-1]
        if isinstance(node, list):
            idx = _index(last, dotted, source, len(node))
            node[idx] = value
        else:
            node[last] = value
    return data


def _index(part: str, dotted: str, source: str, n: int) -> int:
    if not part.lstrip("-").isdigit() or not -n <= int(part) < n:
        raise SceneError(f"{source}: override {dotted}: {part!r} is not an index of a list of {n}")
    return int(part)


def _list_item(node: list, part: str, dotted: str, where: str, source: str):
    return node[_index(part, dotted, source, len(node))]


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "(top level)"


def format_errors(exc: ValidationError, source: str, prefix: str = "", model: type[BaseModel] | None = None) -> str:
    """One line per problem: ``file: key: what was expected, got what``."""
    lines = []
    for err in exc.errors(include_url=False):
        loc = tuple(p for p in err["loc"] if not (isinstance(p, str) and p.startswith(("function-", "tuple["))))
        key = (prefix + "." if prefix and loc else prefix) + _loc(loc) if loc else (prefix or "(top level)")
        kind = err["type"]
        msg = err["msg"]
        if kind == "extra_forbidden":
            parent = _parent_fields(model, loc[:-1])
            hint = f" (expected one of: {', '.join(parent)})" if parent else ""
            lines.append(f"{source}: {key}: unknown key{hint}")
            continue
        if kind == "missing":
            lines.append(f"{source}: {key}: required but missing")
            continue
        msg = msg.replace("Input should be", "expected").replace("Value error, ", "")
        got = err.get("input")
        shown = repr(got) if not isinstance(got, dict) else "a table"
        lines.append(f"{source}: {key}: {msg}, got {shown}" if "input" in err else f"{source}: {key}: {msg}")
    return "\n".join(lines)


def _parent_fields(model: type[BaseModel] | None, loc: tuple) -> list[str]:
    """Field names valid at ``loc`` (for 'unknown key' hints)."""
    if model is None:
        return []
    current: Any = model
    for part in loc:
        if isinstance(part, int) or current is None:
            continue
        fields = getattr(current, "model_fields", {})
        if part in fields:
            current = _model_of(fields[part].annotation)
        else:
            current = None  # dict keys (team names) keep the value model
            continue
    fields = getattr(current, "model_fields", None)
    return sorted(fields) if fields else []


def _model_of(annotation) -> Any:
    import typing

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation) or ():
        found = _model_of(arg)
        if found is not None:
            return found
    return None


def load_scene(name_or_path: str, overrides: Mapping[str, Any] | None = None) -> LoadedScene:
    """Read, override and validate a scene. Raises ``SceneError`` naming the file and the key."""
    source, text = resolve(name_or_path)
    return scene_from_text(text, source, overrides)


def scene_from_text(text: str, source: str, overrides: Mapping[str, Any] | None = None) -> LoadedScene:
    """Validate a scene given as TOML text (e.g. received from a server); ``source`` names it in errors."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from None
    overrides = dict(overrides or {})
    apply_overrides(data, overrides, source)
    try:
        spec = Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(format_errors(exc, source, model=Scene)) from None
    check_world(spec, source)
    return LoadedScene(spec=spec, source=source, text=text, overrides=overrides)


def check_world(spec: Scene, source: str) -> None:
    """Make the scene's world once (its plug-in, its ``params``, its scattered obstacles) and check that no
    robot starts inside an obstacle; SceneError naming the file and the key."""
    from ..worlds import world_class

    try:
        cls = world_class(spec.world.kind)
    except PluginError as exc:
        raise SceneError(f"{source}: world.kind: {exc}") from None
    validate_params(cls.Params, spec.world.params, source, "world.params")
    try:
        geometry = spec.world.geometry()
    except WorldError as exc:
        raise SceneError(f"{source}: {exc}") from None
    for team, tspec in spec.teams.items():
        for m in tspec.members():
            x, y, _ = m.start
            ob = geometry.obstacle_at(x, y)
            if ob is not None and not _starts_above(m, ob.height):
                where = f"teams.{team}.start" if m.squad < 0 else f"teams.{team}.squads[{m.squad}].start"
                raise SceneError(f"{source}: {where}: robot {m.id} starts at ({x:g}, {y:g}), inside obstacle {ob.name}")


def _starts_above(member, top: float) -> bool:
    """A flying robot may start in the air above a low obstacle (its frame clear of the obstacle's top). A
    model or parameters that do not load are left to `check_models`, which names the key."""
    try:
        cls = model_class(member.model)
        if cls.locomotion != "aerial":
            return False
        model = cls(cls.Params.model_validate(dict(member.model_params)))
    except (PluginError, ValidationError):
        return False
    return model.params.start_altitude - model.height / 2 > top


def validate_params(model: type[BaseModel], params: Mapping[str, Any], source: str, key: str) -> BaseModel:
    """Check a plug-in's own parameters (``key`` is where they sit in the scene, e.g. teams.cyan.model_params)."""
    try:
        return model.model_validate(dict(params))
    except ValidationError as exc:
        raise SceneError(format_errors(exc, source, prefix=key, model=model)) from None


def check_models(scene: LoadedScene) -> None:
    """Check every team's robot models and their parameters, and that a flying robot starts below the world's
    ceiling; SceneError naming the file and the key."""
    ceiling = scene.spec.world.ceiling
    for team, tspec in scene.spec.teams.items():
        groups = [(f"teams.{team}", tspec.model, tspec.model_params)]
        groups += [(f"teams.{team}.squads[{k}]", q.model, q.model_params) for k, q in enumerate(tspec.squads)]
        for key, model, params in groups:
            try:
                cls = model_class(model)
            except PluginError as exc:
                raise SceneError(f"{scene.source}: {key}.model: {exc}") from None
            p = validate_params(cls.Params, params, scene.source, f"{key}.model_params")
            start = getattr(p, "start_altitude", None)
            if ceiling is not None and cls.locomotion == "aerial" and start is not None:
                top = start + cls(p).height / 2
                if top >= ceiling:
                    raise SceneError(
                        f"{scene.source}: {key}.model_params.start_altitude: {start:g} m puts the robot's top at "
                        f"{top:g} m, at or above the ceiling (world.ceiling = {ceiling:g} m)"
                    )
