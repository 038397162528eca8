"""``simatch ros2``: the bridge between a run and the ROS 2 graph (docs/ros.md, "ROS 2").

simatch server msl_5v5 --set teams.cyan.strategy=external &
simatch ros2 --team cyan          # cyan's robots driven by cmd_vel; /clock, odom, perception on ROS 2
simatch ros2                      # an observer: /tf, markers, model states, game state (admin credential)
simatch ros2 --build-interfaces   # build simatch_msgs and tf2_msgs as ROS 2 packages (once)
"""

from __future__ import annotations

import os

from . import UsageError
from .server import add_join_options, play_on_server

#: ROS 2 discovery stays on this machine unless asked (``--open-discovery``) or set by the user
DISCOVERY = "ROS_AUTOMATIC_DISCOVERY_RANGE"


def add_parser(sub) -> None:
    p = sub.add_parser(
        "ros2",
        help="put a run on the ROS 2 graph (cmd_vel in; odom, /clock, /tf, markers out)",
        description="Join a run held by 'simatch server' as a bridge to ROS 2 (rclpy, in this process "
        "only): with --team (and --robot) it drives those robots from ROS topics "
        "(/<team>/robot<id>/cmd_vel, dribble, kick) and publishes their perception "
        "(odom, ball, obstacles); with the organiser's credential it also publishes the "
        "ground truth (/tf, markers, model states, every team's game commands). "
        "/clock carries the simulated time. See docs/ros.md.",
    )
    add_join_options(p)
    p.add_argument(
        "--key",
        metavar="FILE",
        help="the credential file (default: the team's with --team, else the organiser's admin.key, as the "
        "server wrote them for this run on this machine)",
    )
    p.add_argument(
        "--team", metavar="TEAM", help="drive this team's robots from ROS 2 (it joins as the team's process)"
    )
    p.add_argument(
        "--robot",
        action="append",
        default=[],
        metavar="TEAM/ID",
        help="drive only this robot (repeatable, one team); the others of the team play as before",
    )
    world = p.add_mutually_exclusive_group()
    world.add_argument(
        "--world",
        dest="world",
        action="store_true",
        default=None,
        help="publish the ground truth (/tf, markers, model states; needs the admin credential; default with it)",
    )
    world.add_argument("--no-world", dest="world", action="store_false", help="do not publish the ground truth")
    p.add_argument(
        "--no-clock",
        dest="clock",
        action="store_false",
        help="do not publish /clock (when another bridge on the same ROS 2 domain does: one clock per domain)",
    )
    p.add_argument(
        "--wait-answers",
        type=float,
        default=0.0,
        metavar="S",
        help="lockstep: wait up to S wall seconds at each control tick for a new cmd_vel of every driven robot "
        "(nodes that answer each odom with one cmd_vel then play a deterministic match; default 0: no wait)",
    )
    p.add_argument(
        "--command-timeout",
        type=float,
        default=None,
        metavar="S",
        help="simulated seconds a robot keeps its last cmd_vel (default 0.5); then the watchdog stops it",
    )
    p.add_argument(
        "--domain-id", type=int, default=None, metavar="N", help="ROS_DOMAIN_ID (default: the environment's, else 0)"
    )
    p.add_argument(
        "--open-discovery",
        action="store_true",
        help="let ROS 2 discovery reach the local network (default: this machine only, "
        f"{DISCOVERY}=LOCALHOST unless set in the environment)",
    )
    p.add_argument(
        "--wait", type=float, default=30.0, metavar="S", help="how long to wait for the server to answer (default 30 s)"
    )
    p.add_argument(
        "--build-interfaces",
        action="store_true",
        help="build simatch_msgs and tf2_msgs as ROS 2 interface packages into this Python's prefix, then exit",
    )
    p.set_defaults(func=main)


def ros_environment(domain_id: int | None, open_discovery: bool) -> None:
    """ROS 2's discovery settings, read by rclpy when the bridge's context starts."""
    if domain_id is not None:
        if not 0 <= domain_id <= 232:
            raise UsageError(f"--domain-id {domain_id}: a ROS 2 domain id is 0..232")
        os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    if open_discovery:
        os.environ[DISCOVERY] = "SUBNET"
    else:
        os.environ.setdefault(DISCOVERY, "LOCALHOST")


def _robots(args) -> tuple[str | None, list[int] | None]:
    from ..bus import topics

    team, robots = args.team, None
    if args.robot:
        robots = []
        for name in args.robot:
            try:
                t, rid = topics.split_robot_name(name)
            except ValueError as exc:
                raise UsageError(str(exc)) from None
            if team is not None and t != team:
                raise UsageError(f"--robot {name}: one bridge drives robots of one team ({team})")
            team = t
            robots.append(rid)
    return team, robots


def main(args) -> int:
    if args.build_interfaces:
        return build_interfaces()
    ros_environment(args.domain_id, args.open_discovery)
    team, robots = _robots(args)
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        raise UsageError(f"ROS 2 is not installed ({exc}): pip install 'simatch[ros2]'") from None
    from ..ros2 import interfaces
    from ..ros2.bridge import COMMAND_TIMEOUT, Bridge

    if interfaces.missing():
        print(
            "simatch ros2: simatch_msgs/tf2_msgs are not built here: their topics (omni_vision, coach, "
            "game_state, /tf, ...) are off; 'simatch ros2 --build-interfaces' builds them once",
            flush=True,
        )
    bridge = Bridge(
        connect=args.connect,
        run=args.run,
        key=args.key,
        team=team,
        robots=robots,
        world=args.world,
        wait_answers=args.wait_answers,
        command_timeout=COMMAND_TIMEOUT if args.command_timeout is None else args.command_timeout,
        clock=args.clock,
        wait=args.wait,
    )
    reason = play_on_server(bridge, interrupted="interrupted; left the run")
    if reason is None:
        return 130
    stats = bridge.stats()
    bad = sum(s["bad"] for s in stats.values())
    got = sum(s["received"] for s in stats.values())
    bridge.say(f"the server ended the run ({reason}); {got} cmd_vel received, {bad} refused as bad")
    return 0


def build_interfaces() -> int:
    from ..ros2 import interfaces

    try:
        done = interfaces.build(say=lambda text: print(f"simatch ros2: {text}", flush=True))
    except interfaces.BuildError as exc:
        raise UsageError(str(exc)) from None
    print(f"simatch ros2: {'built ' + ', '.join(done) if done else 'the interface packages are up to date'}")
    return 0
