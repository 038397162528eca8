"""``simatch server SCENE --listen tcp/127.0.0.1:PORT``: the simulator and the judge of a distributed run.

Team and robot processes (``simatch team``, ``simatch robot``) connect to it. Options are those of
``simatch run`` plus the network ones; it prints the same summary or JSON as ``simatch run``, and in lockstep
mode the same ``state_digest`` for the same scene and seed.
"""

from __future__ import annotations

import contextlib
import signal
import sys

from ..bus.zenoh_bus import DEFAULT_ENDPOINT
from ..config.loader import load_scene
from . import UsageError
from .run import Progress, add_run_options, extensions, match_status, overrides_of, print_result, run_duration


def add_network_options(p, run_help: str) -> None:
    p.add_argument(
        "--run",
        default="default",
        metavar="NAME",
        help=f"{run_help} (default: 'default'); several runs can share a network",
    )


def add_join_options(p) -> None:
    """--connect and --run of a process that joins a server's run (a team, a robot, a ROS bridge)."""
    p.add_argument(
        "--connect",
        default=DEFAULT_ENDPOINT,
        metavar="ENDPOINT",
        help=f"the server's Zenoh endpoint (default {DEFAULT_ENDPOINT})",
    )
    add_network_options(p, "the run to join")


def play_on_server(proc, interrupted: str | None = None) -> str | None:
    """Run ``proc``, a process that joined a server's run (a team's, a ROS bridge's), until the server ends the
    run: the reason it gave; None when interrupted (said, ``interrupted`` or the ticks it played: the process
    left the run). A join the server refuses (a bad credential, an unknown run or team) is a usage error."""
    from ..distributed import interrupt_on_term
    from ..distributed.client import ClientError
    from ..distributed.credentials import CredentialError

    with interrupt_on_term(proc.stop_soon):
        try:
            return proc.run()
        except (ClientError, CredentialError, ValueError) as exc:
            raise UsageError(str(exc)) from None
        except KeyboardInterrupt:
            proc.say(interrupted or f"{proc.what}: interrupted after {proc.ticks} ticks; left the run")
            return None


def add_parser(sub) -> None:
    p = sub.add_parser(
        "server",
        help="run the simulator and judge; teams connect over the network",
        description="Run a scene's simulator, judge and coaches, and wait for the teams (simatch team / simatch "
        "robot) to connect. Lockstep by default: every control tick waits for every connected robot's "
        "command (up to --deadline), so the run equals 'simatch run' bit for bit; --realtime paces it "
        "at wall-clock speed, each process's robots sensing and deciding at their own physics step of "
        "the control period. Prints what 'simatch run' prints.",
    )
    add_run_options(p)
    p.add_argument(
        "--listen",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help=f"Zenoh endpoint to listen on (repeatable; default {DEFAULT_ENDPOINT}, loopback only; "
        f"e.g. tcp/0.0.0.0:7447 to accept other machines)",
    )
    add_network_options(p, "name of this run on the network")
    p.add_argument(
        "--deadline",
        type=float,
        default=5.0,
        metavar="S",
        help="lockstep: longest wait for a process's commands of one tick, wall seconds (default 5; a "
        "process that dies is noticed at once); a process that misses it is not waited for until "
        "it answers again, and the run is no longer bit-exact",
    )
    p.add_argument(
        "--team-timeout",
        type=float,
        default=30.0,
        metavar="S",
        help="how long to wait for the teams to connect before playing without the missing ones (default 30 s)",
    )
    p.add_argument(
        "--credentials",
        metavar="DIR",
        help="folder of the per-team credentials <team>.key (created if missing; default: a private "
        "folder per run under $XDG_RUNTIME_DIR or /tmp, where local teams find them)",
    )
    p.set_defaults(func=main)


def main(args) -> int:
    from ..bus.zenoh_bus import TransportError
    from ..distributed import interrupt_on_term
    from ..distributed.credentials import CredentialError
    from ..distributed.server import Server

    if args.deadline <= 0 or args.team_timeout < 0:
        raise UsageError("--deadline must be positive and --team-timeout not negative")
    scene = load_scene(args.scene, overrides_of(args))
    listen = args.listen or [DEFAULT_ENDPOINT]
    interrupted = False
    with interrupt_on_term():
        try:
            server = Server(
                scene,
                seed=args.seed,
                listen=listen,
                run=args.run,
                realtime=args.realtime,
                deadline=args.deadline,
                team_timeout=args.team_timeout,
                credentials_dir=args.credentials,
            )
        except (TransportError, CredentialError, ValueError) as exc:
            raise UsageError(str(exc)) from None
        with server, contextlib.ExitStack() as stack:
            server.say(
                f"run {args.run!r} ({server.mode}) listening on {', '.join(listen)}; "
                f"team credentials in {server.credentials_dir}"
            )
            # SIGTERM ends the run at a step boundary, as Ctrl-C does (raised wherever it lands, it could come
            # out of a compiled kernel's dispatch as a SystemError); a recording attached below takes it over
            stack.enter_context(server.sim.stopping_on(signal.SIGTERM, KeyboardInterrupt))
            for ext in extensions():
                stack.enter_context(ext.attach(server.sim, args))
            duration = run_duration(server.sim, args)
            try:
                server.wait_for_teams()
                progress = Progress(duration, not args.quiet, match_status(server.sim))
                try:
                    with server.sim.stopping_on(signal.SIGINT, KeyboardInterrupt):  # at a step boundary
                        server.sim.run(seconds=duration, progress=progress)
                finally:
                    progress.close()
            except KeyboardInterrupt:
                interrupted = True
                server.say("interrupted: ending the run")
            server.finish("interrupted" if interrupted else "finished")
            out = server.result()
            stats = server.stats()
    print_result(out, args.json, args.events)
    print("simatch server: " + ", ".join(f"{k} {v}" for k, v in stats.items()), file=sys.stderr)
    return 130 if interrupted else 0
