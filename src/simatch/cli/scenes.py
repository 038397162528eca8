"""``simatch scenes``: the shipped scenes, or one scene's full settings after defaults and overrides, as JSON or
as a complete, commented scene file (``--toml``) that loads back to the same run."""

from __future__ import annotations

import json

from .. import version
from ..config.loader import LoadedScene, load_scene, parse_override, shipped_scenes
from ..worlds import world_class


def add_parser(sub) -> None:
    p = sub.add_parser(
        "scenes",
        help="list the shipped scenes, or show one scene's settings (JSON, or a scene file with --toml)",
        description="Without SCENE: the shipped scenes. With SCENE: every setting of that scene "
        "(defaults filled in, overrides applied), as JSON, and the world as its plug-in made it (world_made: "
        "zones, obstacles given and scattered); with --toml, as a complete scene file with a comment on every "
        "setting, to save and edit: simatch scenes msl_5v5 --toml > my.toml, then simatch run my.toml.",
    )
    p.add_argument("scene", nargs="?", metavar="SCENE", help="a shipped scene name or a path to a .toml file")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene value (dotted path), e.g. match.half_duration=300",
    )
    p.add_argument(
        "--toml",
        action="store_true",
        help="write the scene as a complete, commented TOML scene file (every setting of the scene, its robot "
        "models, strategies and judge, with their defaults) that loads back to the same run",
    )
    p.set_defaults(func=main)


def main(args) -> int:
    if args.scene is None:
        if args.toml or args.overrides:
            from . import UsageError

            raise UsageError("--toml and --set need a SCENE: simatch scenes msl_5v5 --toml > my.toml")
        for name in sorted(shipped_scenes()):
            spec = load_scene(name).spec
            print(f"{name:20s} {spec.description}")
        return 0
    loaded = load_scene(args.scene, dict(parse_override(o) for o in args.overrides))
    if args.toml:
        print(scene_file(loaded, args), end="")
        return 0
    data = loaded.spec.model_dump(mode="json")
    world = world_class(loaded.spec.world.kind)
    for key in world.foreign_keys:  # settings of another kind of world: not this one's
        data["world"].pop(key, None)
    made = loaded.spec.world.geometry().describe()
    made.pop("lines", None)
    data["world_made"] = made  # the world as its plug-in made it (scattered obstacles included)
    print(json.dumps(data, indent=2))
    return 0


def scene_file(loaded: LoadedScene, args) -> str:
    """The complete scene file, with the parameter models of its plug-ins (robot models, strategies, judge)."""
    from ..config.dump import scene_toml

    spec = loaded.spec
    command = " ".join(["simatch scenes", args.scene, *(f"--set {o}" for o in args.overrides), "--toml"])
    header = (
        f"{spec.name}: {spec.description}\n"
        f"Written by '{command}' (simatch {version()}) from {loaded.source}: every setting of the scene, its "
        f"defaults filled in, with what it means.\n"
        f"Run it with 'simatch run FILE.toml'; change any value here or with --set KEY=VALUE."
    )
    return scene_toml(loaded, plugin_params(loaded), header)


def plugin_params(loaded: LoadedScene) -> dict:
    """The parameter model of each plug-in the scene names, by the table its settings sit in."""
    from ..robots import model_class
    from ..scene.judges import judge_class
    from ..strategy import NO_NODES, strategy_class

    spec = loaded.spec
    out = {}
    for team, tspec in spec.teams.items():
        out[f"teams.{team}.model_params"] = getattr(model_class(tspec.model), "Params", None)
        if tspec.strategy not in NO_NODES:
            out[f"teams.{team}.strategy_params"] = getattr(strategy_class(tspec.strategy), "Params", None)
    out["judge"] = getattr(judge_class(spec.judge.kind, loaded.source), "Params", None)
    out["world.params"] = world_class(spec.world.kind).Params
    return out
