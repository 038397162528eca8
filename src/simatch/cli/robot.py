"""``simatch robot TEAM/ID --connect tcp/HOST:PORT``: one robot's nodes alone in this process."""

from __future__ import annotations

from ..bus import topics
from . import UsageError
from .team import add_client_options
from .team import main as team_main


def add_parser(sub) -> None:
    p = sub.add_parser(
        "robot",
        help="run one robot's nodes, connected to a server",
        description="Run one robot's WorldModel + Control in this process, for the run a 'simatch "
        "server' holds. Its team's StrategyPub then runs on the server.",
    )
    p.add_argument("robot", help="the robot, TEAM/ID (e.g. cyan/2)")
    add_client_options(p)
    p.set_defaults(func=main)


def main(args) -> int:
    try:
        team, rid = topics.split_robot_name(args.robot)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    args.team = team
    return team_main(args, robots=[rid])
