"""The teams of a tournament (``--teams``): anything that can play a match.

An entry is written as one of

* a shipped strategy name: ``nubot``, ``simple``;
* a plug-in class: ``striker:StrikerTeam``, ``mypkg.team:MyTeam`` (importable where the matches run);
* a scene's team: ``examples/striker_vs_simple.toml:cyan`` — the strategy, its ``strategy_params``, the robot
  ``model`` and ``model_params`` of that team in that scene file (so variants of one strategy are entries
  with different parameters);

optionally preceded by a name for the standing: ``fast=examples/fast.toml:cyan``. A match puts an entry's
team on one of the tournament scene's colours (its start poses are the colour's); the entry's name is not
part of what identifies a match, so renaming an entry replays nothing.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..config.loader import SceneError, validate_params
from ..errors import UsageError
from ..plugins import PluginError
from ..robots import model_class
from ..strategy import NO_NODES, SHIPPED, strategy_class


@dataclass(frozen=True)
class Entry:
    label: str  # the name in the standing
    strategy: str  # shipped name or package.module:Class
    strategy_params: dict[str, Any] = field(default_factory=dict)
    model: str | None = None  # None: the tournament scene's model for the colour
    model_params: dict[str, Any] | None = None
    written: str = ""  # as the user wrote it

    def identity(self) -> dict:
        """What makes this team play as it does (the match identity includes it; the label does not)."""
        out: dict[str, Any] = {"strategy": self.strategy, "strategy_params": self.strategy_params}
        if self.model is not None:
            out["model"] = self.model
            out["model_params"] = self.model_params or {}
        return out

    def overrides(self, colour: str) -> dict[str, Any]:
        """Scene overrides that put this team on ``colour``."""
        out: dict[str, Any] = {
            f"teams.{colour}.strategy": self.strategy,
            f"teams.{colour}.strategy_params": dict(self.strategy_params),
        }
        if self.model is not None:
            out[f"teams.{colour}.model"] = self.model
            out[f"teams.{colour}.model_params"] = dict(self.model_params or {})
        return out


def parse_entries(items: list[str]) -> list[Entry]:
    """Entries from ``--teams`` values (each a comma-separated list); UsageError for anything wrong."""
    words = [w.strip() for item in items for w in item.split(",") if w.strip()]
    entries = [parse_entry(w) for w in words]
    if len(entries) < 2:
        raise UsageError(f"a tournament needs at least two teams, got {len(entries)}: give --teams A,B[,C...]")
    seen: dict[str, str] = {}
    for e in entries:
        if e.label in seen:
            raise UsageError(
                f"two teams are named {e.label!r} ({seen[e.label]!r} and {e.written!r}): "
                f"name them apart with NAME=TEAM, e.g. {e.label}2={e.written}"
            )
        seen[e.label] = e.written
    same: dict[str, str] = {}
    for e in entries:
        key = canonical(e.identity())
        if key in same:
            raise UsageError(
                f"teams {same[key]!r} and {e.label!r} play the same strategy with the same parameters: every "
                f"match between them would be the same match; give one of them other strategy_params"
            )
        same[key] = e.label
    return entries


def parse_entry(word: str) -> Entry:
    label, sep, spec = word.partition("=")
    if not sep:
        label, spec = "", word
    label, spec = label.strip(), spec.strip()
    if sep and not label:
        raise UsageError(f"team {word!r}: the name before '=' is empty")
    if not spec:
        raise UsageError(f"team {word!r}: nothing to play after '='")
    path, colon, team = spec.rpartition(":")
    if colon and path.endswith(".toml"):
        entry = _scene_team(Path(path), team, word)
        return Entry(**{**entry.__dict__, "label": label or entry.label})
    if spec in NO_NODES:
        raise UsageError(f"team {word!r}: a tournament's teams must play; {spec!r} has no strategy to run here")
    check_strategy(spec, {}, word)
    return Entry(label=label or spec, strategy=spec, written=word)


def _scene_team(path: Path, team: str, word: str) -> Entry:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"team {word!r}: scene file {path} does not exist") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise UsageError(f"team {word!r}: scene file {path} cannot be read: {exc}") from None
    teams = data.get("teams") if isinstance(data.get("teams"), dict) else {}
    if team not in teams or not isinstance(teams[team], dict):
        names = ", ".join(teams) or "none"
        raise UsageError(f"team {word!r}: {path} has no team {team!r} (its teams: {names})")
    t = teams[team]
    strategy = t.get("strategy", "none")
    if not isinstance(strategy, str) or strategy in NO_NODES:
        raise UsageError(f"team {word!r}: teams.{team}.strategy in {path} is {strategy!r}: nothing to play")
    params = t.get("strategy_params", {})
    if not isinstance(params, dict):
        raise UsageError(f"team {word!r}: teams.{team}.strategy_params in {path} is not a table")
    check_strategy(strategy, params, word, f"{path}: teams.{team}.strategy_params")
    model = t.get("model")
    model_params = t.get("model_params")
    if model is not None:
        try:
            cls = model_class(model)
            validate_params(cls.Params, model_params or {}, str(path), f"teams.{team}.model_params")
        except (PluginError, SceneError) as exc:
            raise UsageError(f"team {word!r}: {exc}") from None
    return Entry(
        label=f"{path.stem}:{team}",
        strategy=strategy,
        strategy_params=dict(params),
        model=model,
        model_params=dict(model_params) if model_params is not None else None,
        written=word,
    )


def check_strategy(spec: str, params: dict, word: str, where: str = "") -> None:
    """The strategy loads here and takes ``params``: a typo is refused before any match is started."""
    try:
        cls = strategy_class(spec)
    except PluginError as exc:
        hint = f" (shipped: {', '.join(sorted(SHIPPED))}; a plug-in must be importable: PYTHONPATH)"
        raise UsageError(f"team {word!r}: {exc}{hint}") from None
    model = getattr(cls, "Params", None)
    if model is not None:
        try:
            validate_params(model, params, where or word, "strategy_params")
        except SceneError as exc:
            raise UsageError(f"team {word!r}: {exc}") from None


def canonical(value: Any) -> str:
    """Stable JSON text of plain data (sorted keys), for identities."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)
