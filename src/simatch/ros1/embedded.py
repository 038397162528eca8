"""``--ros1 [TEAMS]``: the run extension that bridges an embedded run (``simatch run``) to a ROS 1 master.

The named teams (comma-separated; bare ``--ros1``: the teams whose scene strategy is ``external``, maybe
none) are played by ROS nodes: their simatch robot nodes and StrategyPub leave the run and the bridge takes
their place. Every robot's perception and game commands, ``/clock`` and the world (``/gazebo/model_states``,
``/gazebo/set_model_state``) are on ROS too, so a ROS user can also just watch. Before the first step the
bridge waits (``--ros1-wait``) until every driven robot has nodes attached. With ``--realtime`` a pacer
paces every physics step, so what ROS sends applies within a step of its arrival.

On a server (``simatch server SCENE --ros1``) the bridge only shows the run on ROS (world, perception, game
commands); a ROS team plays there through its own ``simatch ros1 TEAM --connect ...`` process.
"""

from __future__ import annotations

import contextlib
import sys

from ..errors import UsageError


class Ros1Extension:
    def add_arguments(self, parser) -> None:
        group = parser.add_argument_group("ROS 1 (docs/ros.md)")
        group.add_argument(
            "--ros1",
            nargs="?",
            const="",
            metavar="TEAMS",
            help="bridge the run to a ROS 1 master with the original Simatch's topics; TEAMS (comma-separated) are "
            "played by ROS nodes (default: the teams whose strategy is 'external'); every robot is shown",
        )
        group.add_argument(
            "--ros-master", metavar="URI", help="the ROS master (default: $ROS_MASTER_URI, else http://localhost:11311)"
        )
        group.add_argument(
            "--ros1-wait",
            type=float,
            default=30.0,
            metavar="S",
            help="how long to wait for the driven robots' ROS nodes before the first step (default 30 s)",
        )
        group.add_argument(
            "--ros1-answer-timeout",
            type=float,
            default=1.0,
            metavar="S",
            help="lockstep: longest wait for a robot's answer to one control tick (default 1 s)",
        )

    def attach(self, sim, args):
        teams = getattr(args, "ros1", None)
        if teams is None:
            return contextlib.nullcontext()
        return bridged(sim, args, teams)


def driven_teams(spec, text: str) -> list[str]:
    """The teams named in ``--ros1 TEAMS`` (checked), or those of strategy 'external'."""
    if not text:
        return [t for t, ts in spec.teams.items() if ts.strategy == "external"]
    teams = [t.strip() for t in text.split(",") if t.strip()]
    unknown = [t for t in teams if t not in spec.teams]
    if unknown:
        raise UsageError(f"--ros1: no team {', '.join(unknown)} in this scene (teams: {', '.join(spec.teams)})")
    return teams


@contextlib.contextmanager
def bridged(sim, args, text: str):
    import os

    from .bridge import Options, RosBridge

    spec = sim.scene.spec
    on_server = hasattr(args, "listen")
    teams = driven_teams(spec, text)
    if on_server and text:
        raise UsageError(
            "on a server, --ros1 only shows the run on ROS: a ROS team plays through `simatch ros1 TEAM --connect ...`"
        )
    if on_server:
        teams = []
    if args.ros_master:
        os.environ["ROS_MASTER_URI"] = args.ros_master
    realtime = bool(getattr(args, "realtime", False))
    options = Options(
        teams=teams,
        watch=list(spec.teams),
        world=True,
        lockstep=not realtime,
        answer_timeout=args.ros1_answer_timeout,
        node_name="simatch_bridge",
    )
    for team in teams:  # ROS plays these robots: the scene's nodes for them leave the run
        for node in sim.team_nodes.pop(team, []):
            sim.clock.remove(node)
            sim.robot_nodes.pop(getattr(node, "name", ""), None)
        # and the run says so (a recording of it names them external: its decisions cannot be re-simulated)
        spec.teams[team].strategy = "external"
        sim.scene.overrides[f"teams.{team}.strategy"] = "external"

    def say(text: str) -> None:
        print(f"simatch ros1: {text}", file=sys.stderr, flush=True)

    bridge = RosBridge(spec, options, set_model_state=sim.set_model_state, say=say)
    bridge.connect_ros()
    try:
        if realtime:
            from ..distributed.pacing import Pacer

            sim.clock.add(Pacer(spec.physics.timestep, slack=0.5))
        sim.clock.add(bridge)
        if teams:
            missing = bridge.wait_for_ros(args.ros1_wait)
            if missing:
                say(f"no ROS nodes for {', '.join(missing)} after {args.ros1_wait:g} s: playing without them")
            else:
                say(f"ROS nodes of {', '.join(teams)} attached")
        yield bridge
    finally:
        stats = bridge.stats.as_dict()
        sim.clock.remove(bridge)
        say("bridge stopped: " + ", ".join(f"{k} {v}" for k, v in stats.items()))
