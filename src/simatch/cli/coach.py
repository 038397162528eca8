"""``simatch coach SCENE``: the command-line coach — a console that runs the scene embedded in this process and
takes game commands typed (or piped) one per line.

Chosen design: an interactive console over an embedded run, so it works today with nothing else running
(the Zenoh server is another issue; a console that connects to one can reuse `Console` unchanged, since it
only turns lines into coach commands or referee requests).

* Coach mode (default): as in the paper's first test, each team has its own coach and no referee judges
  (a scene's referee is replaced by per-team coaches). ``--team cyan`` coaches cyan only: commands are sent
  to cyan, from cyan's point of view, and magenta hears nothing from this console.
* Referee mode (``--referee``): the scene's referee judges and the console is its operator (pause, any
  command, move the ball, cards, send off / bring back, automatic judging on/off), sent on the bus as the web
  referee console does.

Input: with a terminal, the run goes on in real time (``--pace``) and each line applies when typed; from a
pipe or ``--script FILE``, lines apply in order and ``run S`` advances S simulated seconds, so a script
gives the same run every time. ``help`` lists the commands.
"""

from __future__ import annotations

import argparse
import queue
import sys
import textwrap
import threading
from collections.abc import Callable
from typing import TextIO

from .. import msgs
from ..bus import topics
from ..config.loader import load_scene
from ..config.schema import JudgeSpec
from ..msgs import game_commands as commands
from . import UsageError
from .run import SCENE_HELP, overrides_of, print_result

HELP = """\
commands (one per line; '#' starts a comment):
  [TEAM] COMMAND [our|opp]   a game command from TEAM's point of view: stop, start, park, dropball,
                             kickoff, throwin, penalty, goalkick, corner, freekick (or a name such as
                             OUR_FREEKICK, or its number); without TEAM: the console's team(s)
  [TEAM] maxvel V | maxw W   the speed / turn-rate limit a coach allows [m/s, rad/s]
  run S                      advance S simulated seconds (live: wait S seconds)
  status                     time, each team's command, the score where a referee judges
  quit                       end the run (so does the end of the input)
referee mode (--referee) also:
  [TEAM] COMMAND ... [at X Y]  the command, with the restart spot (world frame)
  pause | resume | ball X Y | auto on|off | goal TEAM
  yellow TEAM/ID | red TEAM/ID | off TEAM/ID [SECONDS] | back TEAM/ID"""


#: ``simatch coach --help`` (plain text for a terminal: the module's docstring is for the docs)
DESCRIPTION = textwrap.fill(
    "A console that runs SCENE in this process and takes game commands typed (or piped), one per line. "
    "By default each team has a coach and no referee judges (--team T: coach team T only); with --referee the "
    "scene's referee judges and the console is its operator. From a terminal the run goes on at real time "
    "(--pace) and each line applies when typed; from a pipe or --script FILE the lines apply in order and "
    "'run S' advances S simulated seconds, so a script gives the same run every time. Type 'help' at the "
    "prompt for the commands.",
    width=79,
)


class ConsoleError(ValueError):
    """A line the console cannot carry out; printed, the run goes on."""


class Console:
    """Turns typed lines into commands for a running `Simulation` (coach mode) or its referee (referee mode)."""

    def __init__(self, sim, teams: list[str], referee: bool, say: Callable[[str], None]):
        self.sim = sim
        self.teams = teams
        self.referee = referee
        self.say = say
        self.quit = False
        self.pending_run = 0.0
        self._seen = 0
        if referee:
            self.pub = sim.bus.publisher(topics.REFEREE_COMMAND, msgs.RefereeCommand)

    def report(self) -> None:
        """Say which referee requests were refused, and why (the referee applies them at its next step)."""
        events = self.sim.events
        for e in events[self._seen :]:
            if e["type"] == "operator_refused":
                self.say(f"? refused: {e.get('detail', '')}")
        self._seen = len(events)

    def line(self, text: str) -> None:
        words = text.split("#", 1)[0].split()
        if not words:
            return
        head = words[0].lower()
        if head in ("quit", "exit"):
            self.quit = True
        elif head == "help":
            self.say(HELP)
        elif head == "status":
            self.say(self.status())
        elif head == "run":
            self.pending_run += self._number(words, 1, "run S")
        elif self.referee and head in ("pause", "resume", "ball", "auto", "goal", "yellow", "red", "off", "back"):
            self._operator(head, words[1:])
        else:
            self._command(words)

    # --- game commands ---------------------------------------------------------------------------------
    def _command(self, words: list[str]) -> None:
        all_teams = list(self.sim.scene.spec.teams)
        team = ""
        if words[0] in all_teams:
            team, words = words[0], words[1:]
        if not words:
            raise ConsoleError("a team alone is no command")
        spot = None
        if "at" in words:
            k = words.index("at")
            spot = (self._number(words, k + 1, "at X Y"), self._number(words, k + 2, "at X Y"))
            words = words[:k]
        if words[0].lower() in ("maxvel", "maxw"):
            self._limit(team, words)
            return
        try:
            cmd = commands.parse(words)
        except ValueError as exc:
            raise ConsoleError(str(exc)) from None
        if self.referee:
            if 1 <= cmd <= 12 and not team:
                team = self.teams[0] if len(self.teams) == 1 else ""
                if not team:
                    raise ConsoleError(f"{cmd.name} needs a team: e.g. 'cyan {' '.join(words)}'")
            x, y = spot if spot is not None else (0.0, 0.0)
            self._publish(op="command", team=team, command=int(cmd), x=x, y=y, has_position=spot is not None)
            return
        if spot is not None:
            raise ConsoleError("'at X Y' is for the referee (--referee); a coach does not place the ball")
        targets = [team] if team else self.teams
        if team and team not in self.teams:
            raise ConsoleError(f"this console coaches {', '.join(self.teams)}, not {team}")
        if 1 <= cmd <= 12 and len(targets) > 1:
            raise ConsoleError(f"{cmd.name} needs a team: e.g. '{self.teams[0]} {' '.join(words)}'")
        for t in targets:
            self.sim.coaches[t].send(cmd)
            self.say(f"{self.sim.time:9.3f}  {t}: {cmd.name}")

    def _limit(self, team: str, words: list[str]) -> None:
        if self.referee:
            raise ConsoleError("speed limits are a coach's, not the referee's")
        value = self._number(words, 1, f"{words[0]} VALUE")
        if value < 0:
            raise ConsoleError(f"{words[0]} must be >= 0")
        for t in [team] if team else self.teams:
            coach = self.sim.coaches[t]
            coach.send(coach.match_mode, **{"max_vel" if words[0].lower() == "maxvel" else "max_w": value})
            self.say(f"{self.sim.time:9.3f}  {t}: {words[0].lower()} {value:g}")

    # --- referee operator ---------------------------------------------------------------------------------
    def _operator(self, head: str, args: list[str]) -> None:
        if head in ("pause", "resume"):
            self._publish(op=head)
        elif head == "ball":
            self._publish(op="place_ball", x=self._number(args, 0, "ball X Y"), y=self._number(args, 1, "ball X Y"))
        elif head == "auto":
            if not args or args[0] not in ("on", "off"):
                raise ConsoleError("auto on | auto off")
            self._publish(op="auto", on=args[0] == "on")
        elif head == "goal":
            if not args:
                raise ConsoleError("goal TEAM")
            self._publish(op="goal", team=args[0])
        else:
            if not args:
                raise ConsoleError(f"{head} TEAM/ID")
            try:
                team, rid = topics.split_robot_name(args[0])
            except ValueError as exc:
                raise ConsoleError(str(exc)) from None
            if head in ("yellow", "red"):
                self._publish(op="card", team=team, robot=rid, card=head)
            elif head == "off":
                seconds = self._number(args, 1, "off TEAM/ID SECONDS") if len(args) > 1 else 0.0
                self._publish(op="send_off", team=team, robot=rid, seconds=seconds)
            else:
                self._publish(op="return", team=team, robot=rid)

    def _publish(self, **fields) -> None:
        self.pub.put(msgs.new(msgs.RefereeCommand, stamp=self.sim.time, source="cli", **fields))
        self.say(
            f"{self.sim.time:9.3f}  referee <- {fields.get('op')} "
            + " ".join(f"{k}={v}" for k, v in fields.items() if k != "op")
        )

    # --- helpers ---------------------------------------------------------------------------------------
    @staticmethod
    def _number(words: list[str], k: int, usage: str) -> float:
        try:
            value = float(words[k])
        except (IndexError, ValueError):
            raise ConsoleError(f"expected a number: {usage}") from None
        if value != value or value in (float("inf"), float("-inf")):
            raise ConsoleError(f"expected a finite number: {usage}")
        return value

    def status(self) -> str:
        sim = self.sim
        ball = sim.model_states()["ball"]
        parts = [f"t = {sim.time:.3f} s", f"ball ({ball.x:.2f}, {ball.y:.2f})"]
        game = sim.game
        if game is not None:
            parts.append(f"{game['stage']} {game['clock']:.1f} s, {game['phase']}")
            parts.append("score " + ", ".join(f"{t} {n}" for t, n in game["score"].items()))
            parts += [f"{t}: {c['name']}" for t, c in game["commands"].items()]
        else:
            parts += [f"{t}: {c.match_mode.name}" for t, c in sim.coaches.items()]
        return "; ".join(parts)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "coach",
        help="a command-line coach (or referee operator) for a run in this process",
        description=DESCRIPTION,
        epilog=HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", metavar="SCENE", help=SCENE_HELP)
    p.add_argument(
        "--team",
        action="append",
        default=[],
        metavar="TEAM",
        help="coach this team only (repeatable; default: every team)",
    )
    p.add_argument(
        "--referee", action="store_true", help="keep the scene's referee and be its operator instead of coaching"
    )
    p.add_argument(
        "--script",
        type=argparse.FileType("r"),
        metavar="FILE",
        help="read the commands from FILE (default: standard input)",
    )
    p.add_argument(
        "--live",
        action="store_true",
        help="run in real time and apply lines as they come (default when the input is a terminal)",
    )
    p.add_argument(
        "--pace", type=float, default=1.0, metavar="X", help="live mode: simulated seconds per wall second (default 1)"
    )
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="simulated seconds to run in all (default: until 'quit' or the end of the input)",
    )
    p.add_argument("--seed", type=int, default=0, metavar="N", help="random seed (default 0)")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene value, e.g. teams.magenta.strategy=none",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="print exactly one JSON object with the run's results (the console's echo goes to stderr)",
    )
    p.set_defaults(func=main)


def _scene(args):
    scene = load_scene(args.scene, overrides_of(args))
    if not args.referee:
        # coach mode: no referee gives the commands, each team gets its coach (the paper's first test)
        scene.spec = scene.spec.model_copy(update={"judge": JudgeSpec(kind="none")})
    return scene


def main(args) -> int:
    from ..simulation import Simulation

    if args.pace <= 0:
        raise UsageError("--pace must be positive")
    if args.duration is not None and args.duration <= 0:
        raise UsageError("--duration must be positive")
    scene = _scene(args)
    teams = list(scene.spec.teams)
    for t in args.team:
        if t not in teams:
            raise UsageError(f"no team named {t!r} in {scene.name} (teams: {', '.join(teams)})")
    echo: TextIO = sys.stderr if args.json else sys.stdout
    source = args.script or sys.stdin
    live = args.live or (args.script is None and sys.stdin.isatty())
    with Simulation(scene, seed=args.seed) as sim:
        if args.referee and not sim.judge.gives_commands:
            raise UsageError(
                f"scene {scene.name} has no referee (judge '{scene.spec.judge.kind}'): drop --referee to coach"
            )
        console = Console(sim, args.team or teams, args.referee, lambda s: print(s, file=echo, flush=True))
        sim.step()
        if live:
            _live(sim, console, source, args, echo)
        else:
            _scripted(sim, console, source, args, echo)
        out = sim.result()
    print_result(out, args.json)
    return 0


def _apply(console: Console, text: str, echo: TextIO) -> None:
    try:
        console.line(text)
    except (ConsoleError, ValueError) as exc:
        print(f"? {exc}", file=echo, flush=True)
    if console.referee:
        console.sim.step()  # the referee takes the request at its next step
        console.report()


def _scripted(sim, console: Console, source: TextIO, args, echo: TextIO) -> None:
    end = args.duration
    for text in source:
        _apply(console, text, echo)
        if console.pending_run:
            seconds = console.pending_run if end is None else min(console.pending_run, max(0.0, end - sim.time))
            console.pending_run = 0.0
            sim.run(seconds=seconds)
        if console.quit or sim.done or (end is not None and sim.time >= end - 1e-9):
            return
    if end is not None and sim.time < end:
        sim.run(seconds=end - sim.time)


def _live(sim, console: Console, source: TextIO, args, echo: TextIO) -> None:
    lines: queue.Queue = queue.Queue()

    def read() -> None:
        for text in source:
            lines.put(text)
        lines.put(None)

    threading.Thread(target=read, daemon=True, name="coach-input").start()
    sim.pace = args.pace
    if source is sys.stdin and sys.stdin.isatty():
        print("simatch coach: type 'help' for the commands, 'quit' to end", file=echo, flush=True)
    while not console.quit and not sim.done:
        if args.duration is not None and sim.time >= args.duration - 1e-9:
            break
        try:
            while True:
                text = lines.get_nowait()
                if text is None:
                    console.quit = True
                    break
                _apply(console, text, echo)
                console.pending_run = 0.0  # live: the clock runs anyway
        except queue.Empty:
            pass
        chunk = 0.1 if args.duration is None else min(0.1, args.duration - sim.time)
        if chunk > 0 and not console.quit:
            sim.run(seconds=chunk)
            console.report()
