"""The ``simatch`` command. Each subcommand lives in its own module with ``add_parser`` and ``main``."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from .. import version
from ..config.loader import SceneError
from ..errors import UsageError
from ..plugins import PluginError

__all__ = ["SUBCOMMANDS", "UsageError", "build_parser", "main"]

#: subcommand modules, in the order ``simatch --help`` lists them
SUBCOMMANDS = [
    "simatch.cli.run",
    "simatch.cli.bench",
    "simatch.cli.scenes",
    "simatch.cli.replay",
    "simatch.cli.export",
    "simatch.cli.recover",
    "simatch.cli.report",
    "simatch.cli.tournament",
    "simatch.cli.coach",
    "simatch.cli.serve",
    "simatch.cli.server",
    "simatch.cli.team",
    "simatch.cli.robot",
    "simatch.cli.ros1",
    "simatch.cli.ros2",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="simatch",
        description="Simulation of highly dynamic confrontations between multi-robot systems "
        "(RoboCup MSL soccer and beyond).",
    )
    parser.add_argument("--version", action="version", version=f"simatch {version()}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        importlib.import_module(name).add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2), format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (SceneError, PluginError, UsageError) as exc:
        print(f"simatch: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("simatch: interrupted", file=sys.stderr)
        return 130
