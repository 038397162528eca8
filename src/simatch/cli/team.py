"""``simatch team TEAM --connect tcp/HOST:PORT``: one team's nodes in this process, playing on a server."""

from __future__ import annotations

from ..config.loader import parse_override
from .server import add_join_options, play_on_server


def add_client_options(p) -> None:
    add_join_options(p)
    p.add_argument(
        "--key",
        metavar="FILE",
        help="this team's credential file (default: the one the server wrote for this run on this machine)",
    )
    p.add_argument(
        "--strategy",
        metavar="SPEC",
        help="the strategy to play (a shipped name or package.module:Class; default: the scene's)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a strategy parameter (repeatable), e.g. --param vx=1.0",
    )
    p.add_argument(
        "--wait", type=float, default=30.0, metavar="S", help="how long to wait for the server to answer (default 30 s)"
    )


def add_parser(sub) -> None:
    p = sub.add_parser(
        "team",
        help="run one team's robots, connected to a server",
        description="Run every robot node (WorldModel + Control) of TEAM and its StrategyPub in this "
        "process, for the run a 'simatch server' holds. The scene comes from the server; "
        "the strategy from the scene or --strategy.",
    )
    p.add_argument("team", help="the team to play, e.g. cyan")
    add_client_options(p)
    p.set_defaults(func=main)


def main(args, robots: list[int] | None = None) -> int:
    from ..distributed.client import TeamProcess

    params = dict(parse_override(p) for p in args.param)
    proc = TeamProcess(
        args.team,
        robots,
        connect=args.connect,
        run=args.run,
        key=args.key,
        strategy=args.strategy,
        params=params,
        wait=args.wait,
    )
    reason = play_on_server(proc)
    if reason is None:
        return 130
    stats = proc.stats
    proc.say(
        f"{proc.what}: the server ended the run ({reason}) after {proc.ticks} ticks"
        + (f", {proc.skipped} skipped" if proc.skipped else "")
        + (f"; dropped {stats.malformed} malformed sample(s)" if stats.malformed else "")
    )
    return 0
