"""``simatch scenes``: the shipped scenes, or one scene's full settings after defaults and overrides."""

from __future__ import annotations

import json

from ..config.loader import load_scene, parse_override, shipped_scenes
from ..worlds import world_class


def add_parser(sub) -> None:
    p = sub.add_parser(
        "scenes",
        help="list the shipped scenes, or show one scene's settings",
        description="Without SCENE: the shipped scenes. With SCENE: every setting of that scene "
        "(defaults filled in, overrides applied), as JSON, and the world as its plug-in made it (world_made: "
        "zones, obstacles given and scattered).",
    )
    p.add_argument("scene", nargs="?", help="a shipped scene name or a path to a .toml file")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene value (dotted path), e.g. match.half_duration=300",
    )
    p.set_defaults(func=main)


def main(args) -> int:
    if args.scene is None:
        for name in sorted(shipped_scenes()):
            spec = load_scene(name).spec
            print(f"{name:20s} {spec.description}")
        return 0
    loaded = load_scene(args.scene, dict(parse_override(o) for o in args.overrides))
    data = loaded.spec.model_dump(mode="json")
    world = world_class(loaded.spec.world.kind)
    for key in world.foreign_keys:  # settings of another kind of world: not this one's
        data["world"].pop(key, None)
    made = loaded.spec.world.geometry().describe()
    made.pop("lines", None)
    data["world_made"] = made  # the world as its plug-in made it (scattered obstacles included)
    print(json.dumps(data, indent=2))
    return 0
