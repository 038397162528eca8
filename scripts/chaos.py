#!/usr/bin/env python3
"""Chaos test of a distributed run: faults injected into a recorded match, then checked.

    .venv/bin/python scripts/chaos.py                       # lockstep, then real time: msl_5v5, 30 s each
    .venv/bin/python scripts/chaos.py --mode realtime --duration 60 --faults 12 --json
    .venv/bin/python scripts/chaos.py --layout robot --set teams.cyan.strategy=simple

It starts a `simatch server` that records the match, and the team or robot processes (``--layout``: one per
team, one per robot, or ``mixed``: cyan one team process, magenta one per robot). Each client process
reaches the server through a proxy of its own on loopback, so that its traffic can be held up. While the
match runs it injects random faults, one at a time, each into a random client process:

* ``kill``: SIGKILL, then the process is started again (expected: ``process_lost``, then ``process_joined``);
* ``stop``: SIGSTOP for a while, then SIGCONT (expected: ``process_late``);
* ``restart``: SIGTERM, then started again (expected: ``process_left``, then ``process_joined``);
* ``stall``: its proxy holds every byte back for a while, then lets them through (Zenoh's traffic dropped for
  that time: expected ``process_late``);
* ``delay``: its proxy delays every byte by some hundreds of milliseconds for a while (expected
  ``process_late``);
* ``cut``: its proxy closes its connection (expected ``process_lost``; its session connects again and the
  process joins again: ``process_joined``; started again if it ended).

Afterwards it checks that the server never stopped (it ran the whole duration and exited 0), that each fault
appears in the run's event log (the events above, naming the process by its id, which holds its pid), that
the recording is complete (finalised, every physics step's model states from the first to the last, no
damaged part) and that ``simatch replay --verify`` reproduces the run bit for bit from its recorded inputs.
Exit status 0 if every check passed, 1 otherwise; ``--json`` prints one JSON report. Assertions are about
correctness, never speed: on a loaded machine a real-time run may fall behind, and that is not a failure.

Everything stays on loopback (127.0.0.1); every process it starts is stopped before it exits.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIMATCH = [sys.executable, "-m", "simatch"]
FAULTS = ("kill", "stop", "restart", "stall", "delay", "cut")
#: what the server logs for each fault (any one of them, for the faulty process)
EXPECTED = {
    "kill": ("process_lost",),
    "stop": ("process_late",),
    "restart": ("process_left",),
    "stall": ("process_late", "process_lost"),
    "delay": ("process_late", "process_lost"),
    "cut": ("process_lost", "process_late"),
}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# --- a proxy per client process: holds up, delays or cuts its traffic ------------------------------------------
class Proxy:
    """Forwards TCP connections from 127.0.0.1:port to the server's port, both ways, each byte released at
    ``max(arrival + delay, held_until)``; `cut` closes every connection it carries."""

    def __init__(self, target: int):
        self.target = target
        self.delay = 0.0
        self.held_until = 0.0
        self._lock = threading.Lock()
        self._conns: list[socket.socket] = []
        self._listen = socket.socket()
        self._listen.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listen.bind(("127.0.0.1", 0))
        self._listen.listen(8)
        self.port = self._listen.getsockname()[1]
        self._closed = False
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while not self._closed:
            try:
                client, _ = self._listen.accept()
            except OSError:
                return
            try:
                upstream = socket.create_connection(("127.0.0.1", self.target), timeout=5)
            except OSError:
                client.close()
                continue
            for s in (client, upstream):
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self._lock:
                self._conns += [client, upstream]
            for a, b in ((client, upstream), (upstream, client)):
                queue: list = []
                cond = threading.Condition()
                threading.Thread(target=self._read, args=(a, b, queue, cond), daemon=True).start()
                threading.Thread(target=self._write, args=(b, a, queue, cond), daemon=True).start()

    def _read(self, src: socket.socket, dst: socket.socket, queue: list, cond: threading.Condition) -> None:
        while True:
            try:
                data = src.recv(65536)
            except OSError:
                data = b""
            with cond:
                queue.append((max(time.monotonic() + self.delay, self.held_until), data))
                cond.notify()
            if not data:
                return

    def _write(self, dst: socket.socket, src: socket.socket, queue: list, cond: threading.Condition) -> None:
        while True:
            with cond:
                while not queue:
                    cond.wait()
                due, data = queue[0]
            wait = max(due, self.held_until) - time.monotonic()
            if wait > 0:
                time.sleep(min(wait, 0.05))
                continue
            with cond:
                queue.pop(0)
            if not data:
                for s in (dst, src):
                    _close(s)
                return
            try:
                dst.sendall(data)
            except OSError:
                for s in (dst, src):
                    _close(s)
                return

    def hold(self, seconds: float) -> None:
        self.held_until = time.monotonic() + seconds

    def cut(self) -> None:
        with self._lock:
            conns, self._conns = self._conns, []
        for s in conns:
            _close(s)

    def close(self) -> None:
        self._closed = True
        _close(self._listen)
        self.cut()


def _close(s: socket.socket) -> None:
    try:
        s.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass
    try:
        s.close()
    except OSError:
        pass


# --- the processes of the run -------------------------------------------------------------------------------
class Client:
    """A team or robot process of the run, behind its own proxy."""

    def __init__(self, run: Run, who: str):
        self.run, self.who = run, who
        self.kind = "robot" if "/" in who else "team"
        self.proxy = Proxy(run.port)
        self.proc: subprocess.Popen | None = None
        self.pids: list[int] = []
        self.starts = 0

    def start(self) -> None:
        team = self.who.split("/")[0]
        log = open(self.run.out / f"{self.kind}-{self.who.replace('/', '-')}-{self.starts}.log", "w")
        self.starts += 1
        args = [self.kind, self.who, "--connect", f"tcp/127.0.0.1:{self.proxy.port}", "--run", self.run.name]
        args += ["--key", str(self.run.creds / f"{team}.key"), "--wait", "60"]
        self.proc = subprocess.Popen(
            SIMATCH + args, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT, env=self.run.env, start_new_session=True
        )
        log.close()
        self.pids.append(self.proc.pid)

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def signal(self, sig: int) -> None:
        if self.alive:
            os.kill(self.proc.pid, sig)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            try:
                os.kill(self.proc.pid, signal.SIGCONT)
                self.proc.send_signal(signal.SIGKILL)
            except ProcessLookupError:
                pass
        if self.proc is not None:
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                pass
        self.proxy.close()


class Run:
    """One recorded match with its server and client processes."""

    def __init__(self, args, mode: str, out: Path):
        self.args, self.mode, self.out = args, mode, out
        self.port = _free_port()
        self.name = f"chaos{os.getpid()}{mode[0]}{self.port}"
        self.creds = out / "creds"
        self.recording = out / "match.mcap"
        self.env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        self.server: subprocess.Popen | None = None
        self.clients: list[Client] = []
        self._stderr_path = out / "server.err"

    def start(self) -> None:
        a = self.args
        cmd = SIMATCH + ["server", a.scene, "--listen", f"tcp/127.0.0.1:{self.port}", "--run", self.name]
        cmd += ["--credentials", str(self.creds), "--duration", str(a.duration), "--seed", str(a.seed)]
        cmd += ["--record", str(self.recording), "--json", "--quiet", "--team-timeout", "120"]
        cmd += ["--deadline", str(a.deadline)] + (["--realtime"] if self.mode == "realtime" else [])
        for kv in a.set:
            cmd += ["--set", kv]
        self._out = open(self.out / "server.json", "w+")
        self._err = open(self._stderr_path, "w+")
        self.server = subprocess.Popen(cmd, stdout=self._out, stderr=self._err, cwd=ROOT, env=self.env)
        deadline = time.monotonic() + 60
        while not (self.creds / "admin.key").exists():  # the server writes the credentials as it starts
            if self.server.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the server did not start:\n{self.server_log()}")
            time.sleep(0.05)
        for who in self.client_names():
            client = Client(self, who)
            client.start()
            self.clients.append(client)

    def client_names(self) -> list[str]:
        from simatch.config.loader import load_scene

        spec = load_scene(self.args.scene, _overrides(self.args.set)).spec
        names = []
        for team in spec.teams:
            if spec.teams[team].strategy in ("none", "external"):
                continue
            per_robot = self.args.layout == "robot" or (self.args.layout == "mixed" and team != next(iter(spec.teams)))
            names += [f"{team}/{rid}" for rid in spec.teams[team].robot_ids()] if per_robot else [team]
        return names

    def server_log(self) -> str:
        self._err.flush()
        return self._stderr_path.read_text(errors="replace")

    def wait_for(self, text: str, timeout: float, after: int = 0) -> bool:
        """Wait until the server's log says ``text`` (after its first ``after`` characters)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.server_log()[after:]:
                return True
            if self.server.poll() is not None:
                return False
            time.sleep(0.05)
        return False

    def playing(self) -> bool:
        return self.server is not None and self.server.poll() is None

    def sim_time(self) -> float:
        """Simulated seconds recorded so far (the recording grows every half second)."""
        from simatch.record import Recording, RecordingError

        try:
            return Recording(self.recording).duration
        except (RecordingError, OSError):
            return 0.0

    def stop(self) -> None:
        for c in self.clients:
            c.stop()
        if self.server is not None and self.server.poll() is None:
            self.server.send_signal(signal.SIGINT)
            try:
                self.server.wait(30)
            except subprocess.TimeoutExpired:
                self.server.kill()
                self.server.wait(10)


def _overrides(pairs: list[str]) -> dict:
    from simatch.config.loader import parse_override

    return dict(parse_override(kv) for kv in pairs)


# --- faults -------------------------------------------------------------------------------------------------
def inject(run: Run, rng: random.Random, kind: str, hold: float) -> dict:
    """One fault into a random client process; returns what was done (and the pid the server knew)."""
    client = rng.choice([c for c in run.clients if c.alive] or run.clients)
    fault = {"kind": kind, "target": client.who, "pid": client.proc.pid, "sim": round(run.sim_time(), 3)}
    mark = len(run.server_log())
    if kind == "kill":
        client.signal(signal.SIGKILL)
        client.proc.wait(10)
        run.wait_for("was lost", 10, mark)
        client.start()
    elif kind == "restart":
        client.signal(signal.SIGTERM)
        try:
            client.proc.wait(20)
        except subprocess.TimeoutExpired:
            client.signal(signal.SIGKILL)
            client.proc.wait(10)
        client.start()
    elif kind == "stop":
        client.signal(signal.SIGSTOP)
        run.wait_for("is late", hold, mark)
        time.sleep(0.2)
        client.signal(signal.SIGCONT)
    elif kind == "stall":
        client.proxy.hold(hold)
        time.sleep(hold)
    elif kind == "delay":
        client.proxy.delay = rng.uniform(0.3, 0.6) if run.mode == "realtime" else run.args.deadline * 1.5
        time.sleep(hold)
        client.proxy.delay = 0.0
    elif kind == "cut":
        client.proxy.cut()
        run.wait_for("was lost", 10, mark)
    # the process is back in the run before the next fault (a restarted one warms up first; a cut one
    # connects again and joins again)
    back = run.wait_for("joined", 90, mark) if kind in ("kill", "restart", "cut") else True
    if kind == "cut" and not back and not client.alive:
        mark = len(run.server_log())
        client.start()
        back = run.wait_for("joined", 90, mark)
    fault["rejoins"] = client.proc.pid if kind in ("kill", "restart", "cut") else None
    fault["back"] = back
    return fault


def check(run: Run, faults: list[dict], code: int) -> dict:
    """Every check the chaos run makes afterwards (see the module's docstring)."""
    from simatch.bus import topics
    from simatch.record import Recording, verify

    out: dict = {"checks": {}, "problems": []}
    checks = out["checks"]
    result = {}
    try:
        result = json.loads((run.out / "server.json").read_text())
    except (OSError, ValueError) as exc:
        out["problems"].append(f"the server printed no result: {exc}")
    checks["server_ran_to_the_end"] = code == 0 and abs(result.get("sim_seconds", -1) - run.args.duration) < 1e-6
    rec = Recording(run.recording)
    events = [m for _, _, m in rec.messages(topics={topics.EVENTS})]
    out["events"] = {}
    for e in events:
        out["events"][e.type] = out["events"].get(e.type, 0) + 1
    found = []
    for n, fault in enumerate(faults):
        # what the server logged about the faulty process from the fault on, up to the next fault
        start = fault["sim"]
        end = faults[n + 1]["sim"] if n + 1 < len(faults) else float("inf")
        window = [e for e in events if start <= e.stamp < end]
        tag = f"-{fault['pid']}-"
        fault["logged"] = sorted({e.type for e in window if tag in e.detail and e.type in EXPECTED[fault["kind"]]})
        if fault.get("rejoins"):
            again = f"-{fault['rejoins']}-"
            fault["rejoined"] = any(e.type == "process_joined" and again in e.detail for e in window)
        found.append(bool(fault["logged"]) and fault.get("rejoined", True))
    checks["every_fault_in_the_event_log"] = all(found)
    steps = [int(m.step) for _, _, m in rec.messages(topics={topics.MODEL_STATES})]
    expected_steps = round(run.args.duration / float(rec.metadata.get("dt", "0.005")))
    checks["recording_complete"] = (
        rec.finalised
        and not rec.problems
        and (rec.end or {}).get("status") == "complete"
        and steps == list(range(expected_steps))
    )
    if not checks["recording_complete"]:
        out["problems"] += rec.problems + [
            f"recorded steps {steps[:1]}..{steps[-1:]}, {len(steps)} of {expected_steps}"
        ]
    verdict = verify(run.recording)
    out["verify"] = verdict.as_dict()
    checks["reproduced_from_inputs"] = verdict.identical and verdict.complete and verdict.mode == "inputs"
    out["result"] = {k: result.get(k) for k in ("sim_seconds", "wall_seconds", "rtf", "state_digest")}
    out["ok"] = all(checks.values())
    return out


def play(args, mode: str, out: Path, say) -> dict:
    rng = random.Random(args.fault_seed)
    run = Run(args, mode, out)
    faults: list[dict] = []
    kinds = [k.strip() for k in args.kinds.split(",")]
    unknown = set(kinds) - set(FAULTS)
    if unknown:
        raise SystemExit(f"chaos.py: unknown fault(s) {', '.join(sorted(unknown))}; faults are {', '.join(FAULTS)}")
    code = -1
    try:
        run.start()
        say(f"{mode}: server on port {run.port}, {len(run.clients)} client process(es); waiting for them to join")
        deadline = time.monotonic() + 180
        while run.playing() and run.server_log().count("joined") < len(run.clients):
            if time.monotonic() > deadline:
                raise RuntimeError(f"the clients did not join:\n{run.server_log()}")
            time.sleep(0.1)
        hold = args.hold if args.hold is not None else (2.0 * args.deadline + 0.5 if mode == "lockstep" else 1.0)
        # faults while there is time left for the faulty process to come back before the end
        while run.playing() and len(faults) < args.faults and run.sim_time() < args.until * args.duration:
            time.sleep(rng.uniform(0.2, args.gap))
            if not run.playing():
                break
            kind = kinds[len(faults) % len(kinds)] if args.cycle else rng.choice(kinds)
            fault = inject(run, rng, kind, hold)
            faults.append(fault)
            say(f"{mode}: fault {len(faults)}: {fault['kind']} {fault['target']} (pid {fault['pid']})")
            # what the server logged about it is on disk before the next fault starts (the recording is
            # written half a simulated second at a time): each fault's events fall between its start and the next's
            done = run.sim_time()
            deadline = time.monotonic() + 30
            while run.playing() and run.sim_time() < done + 1.0 and time.monotonic() < deadline:
                time.sleep(0.1)
        code = run.server.wait(args.timeout)
    except subprocess.TimeoutExpired:
        say(f"{mode}: the server did not end within {args.timeout} s")
    finally:
        run.stop()
    report = {"mode": mode, "faults": faults, "recording": str(run.recording), "server_exit": code}
    report.update(check(run, faults, code))
    return report


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--scene", default="msl_5v5")
    p.add_argument("--mode", choices=("lockstep", "realtime", "both"), default="both")
    p.add_argument("--duration", type=float, default=30.0, help="simulated seconds of each match (default 30)")
    p.add_argument("--faults", type=int, default=6, help="faults per match (default 6)")
    p.add_argument("--kinds", default=",".join(FAULTS), help=f"which faults (default {','.join(FAULTS)})")
    p.add_argument("--cycle", action="store_true", help="faults in the order of --kinds (default: at random)")
    p.add_argument("--layout", choices=("team", "robot", "mixed"), default="mixed")
    p.add_argument("--seed", type=int, default=0, help="the match's seed")
    p.add_argument("--fault-seed", type=int, default=None, help="seed of the faults' choices (default: random)")
    p.add_argument("--deadline", type=float, default=0.5, help="the lockstep server's --deadline (default 0.5 s)")
    p.add_argument("--hold", type=float, default=None, help="how long a stop, stall or delay lasts [s]")
    p.add_argument("--gap", type=float, default=2.0, help="longest wait between two faults [s] (default 2)")
    p.add_argument("--until", type=float, default=0.6, help="no fault after this fraction of the match (default 0.6)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="scene overrides")
    p.add_argument("--out", help="folder for the recordings and logs (default: a new temporary one, kept)")
    p.add_argument("--timeout", type=float, default=900.0, help="longest wait for a match to end [s]")
    p.add_argument("--json", action="store_true", help="print one JSON report")
    args = p.parse_args(argv)
    if args.fault_seed is None:
        args.fault_seed = random.SystemRandom().randrange(1 << 31)
    base = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="simatch-chaos-"))
    base.mkdir(parents=True, exist_ok=True)

    def say(text: str) -> None:
        if not args.json:
            print(text, file=sys.stderr, flush=True)

    reports = []
    for mode in ("lockstep", "realtime") if args.mode == "both" else (args.mode,):
        out = base / mode
        out.mkdir(exist_ok=False)
        reports.append(play(args, mode, out, say))
    ok = all(r["ok"] for r in reports)
    if args.json:
        print(json.dumps({"ok": ok, "fault_seed": args.fault_seed, "runs": reports}))
    else:
        for r in reports:
            print(f"{r['mode']}: {'ok' if r['ok'] else 'FAILED'}  ({r['recording']})")
            for f in r["faults"]:
                logged = ", ".join(f.get("logged", [])) or "-"
                print(f"  {f['kind']:8s} {f['target']:10s} pid {f['pid']:<8d} logged: {logged}")
            for name, passed in r["checks"].items():
                print(f"  {'ok    ' if passed else 'FAILED'} {name}")
            for problem in r["problems"]:
                print(f"  problem: {problem}")
            v = r["verify"]
            print(f"  verify: {v.get('identical')} ({v.get('compared')} samples, mode {v.get('mode')})")
        print(f"fault seed {args.fault_seed}; files in {base}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
