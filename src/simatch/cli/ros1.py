"""``simatch ros1 TEAM --connect tcp/HOST:PORT``: a team of ROS 1 nodes plays in a distributed run, through
a bridge that speaks the original Simatch's topics on a ROS master (docs/ros.md). ``simatch ros1
--print-env`` prints the shell settings for ROS tools to know the message packages."""

from __future__ import annotations

import os
import sys

from . import UsageError
from .server import add_join_options, play_on_server


def add_parser(sub) -> None:
    p = sub.add_parser(
        "ros1",
        help="play a team of ROS 1 nodes (the original Simatch's interface) on a server",
        description="Join the run a 'simatch server' holds as TEAM's process, and bridge TEAM's robots to a ROS 1 "
        "master with the original Simatch's topics, names, units and messages (nubot_common, gazebo_msgs): "
        "perception, game commands and /clock out, velcmd/actioncmd/strategy in. In lockstep the bridge waits "
        "for each robot's answer to every control tick. With --print-env, print the shell settings that let "
        "ROS tools (rosmsg, rostopic, roslaunch) find the message packages and the example team, and exit.",
    )
    p.add_argument("team", nargs="?", help="the team whose robots ROS plays, e.g. cyan")
    add_join_options(p)
    p.add_argument(
        "--key",
        metavar="FILE",
        help="the team's credential (default: the one the server wrote for this run on this machine); the "
        "organiser's admin.key also bridges the world (/gazebo/model_states, /gazebo/set_model_state)",
    )
    p.add_argument(
        "--wait", type=float, default=30.0, metavar="S", help="how long to wait for the server (default 30 s)"
    )
    p.add_argument(
        "--ros-master", metavar="URI", help="the ROS master (default: $ROS_MASTER_URI, else http://localhost:11311)"
    )
    p.add_argument(
        "--wait-ros",
        type=float,
        default=30.0,
        metavar="S",
        help="how long to wait for every robot's ROS nodes before joining (default 30 s)",
    )
    p.add_argument(
        "--answer-timeout",
        type=float,
        default=1.0,
        metavar="S",
        help="lockstep: longest wait for a robot's answer to one control tick (default 1 s; keep it below the "
        "server's --deadline)",
    )
    p.add_argument(
        "--no-clock", action="store_true", help="do not publish /clock (another bridge on the same master does)"
    )
    p.add_argument(
        "--no-strategy-relay",
        action="store_true",
        help="do not relay <robot>/nubotcontrol/strategy to <prefix>/nubotcontrol/strategy (the team runs its own "
        "relay; the bridge also steps aside by itself when it sees one)",
    )
    p.add_argument("--print-env", action="store_true", help="print 'export' lines for a shell, and exit")
    p.set_defaults(func=main)


def main(args) -> int:
    from ..ros1.rosenv import shell_exports

    if args.print_env:
        print(shell_exports(master=args.ros_master))
        return 0
    if not args.team:
        raise UsageError("ros1: give the TEAM whose robots ROS plays (or --print-env)")
    if args.ros_master:
        os.environ["ROS_MASTER_URI"] = args.ros_master
    from ..ros1.client import BridgeProcess

    proc = BridgeProcess(
        args.team,
        connect=args.connect,
        run=args.run,
        key=args.key,
        wait=args.wait,
        answer_timeout=args.answer_timeout,
        wait_ros=args.wait_ros,
        clock=not args.no_clock,
        strategy_relay=not args.no_strategy_relay,
    )
    reason = play_on_server(proc)
    if reason is None:
        return 130
    bridge = proc.bridge
    stats = bridge.stats.as_dict() if bridge is not None else {}
    proc.say(
        f"{proc.what}: the server ended the run ({reason}) after {proc.ticks} ticks; bridge: "
        + ", ".join(f"{k} {v}" for k, v in stats.items())
    )
    sys.stdout.flush()
    return 0
