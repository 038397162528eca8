"""One match of a tournament, played where a worker runs it (a Ray task, or the plain loop): `play_match`.

It takes a plain job (the scene's text and overrides, the seed, the teams' names, the time limit, where to
record) and returns the match's row and analysis as plain data, whatever happened: a match that raises (a
plug-in failing to build, a scene it cannot play) comes back as a row with status ``error`` and the error,
one that runs past its time limit as ``timeout`` with where it was stuck. Nothing it returns depends on the
process it ran in but ``wall_seconds`` and ``worker``: the same job gives the same row (same state digest).

The time limit is kept here by a timer signal whose handler raises `MatchTimeout` — a BaseException, so the
strategies' error guard (which catches Exception) cannot swallow it — in the thread running the match. Code
that never returns to Python (a compiled loop) does not see it; the driver then ends the worker (see
`simatch.tournament.runner`).
"""

from __future__ import annotations

import datetime
import os
import signal
import socket
import threading
import time
import traceback
from pathlib import Path

from .. import version
from ..config.loader import scene_from_text
from ..record import Recorder
from ..report.live import LiveAnalysis
from ..simulation import Simulation


class MatchTimeout(BaseException):
    """The match ran past its time limit."""


def worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def _where(exc: BaseException) -> str:
    """The innermost frame of the traceback that is not simatch's own (the plug-in's), else the innermost."""
    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return ""
    package = str(Path(__file__).resolve().parents[1])
    theirs = [f for f in frames if not str(Path(f.filename).resolve()).startswith(package)]
    f = (theirs or frames)[-1]
    return f"{f.filename}:{f.lineno} in {f.name}"


class _Timer:
    """SIGALRM after ``seconds`` raises MatchTimeout in the main thread (nothing elsewhere: no signals there)."""

    def __init__(self, seconds: float | None):
        self.seconds = seconds
        self.armed = False
        self.previous = None

    def __enter__(self):
        if self.seconds and threading.current_thread() is threading.main_thread():

            def fire(signum, frame):
                raise MatchTimeout(f"the match ran longer than its limit of {self.seconds:g} s of wall time")

            self.previous = signal.signal(signal.SIGALRM, fire)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
            self.armed = True
        return self

    def __exit__(self, *exc) -> None:
        if self.armed:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self.previous)


def play_match(job: dict) -> dict:
    """Play the match of ``job`` (see `simatch.tournament.tournament.Tournament.job`); returns
    ``{"row": ..., "analysis": ...}`` (analysis None unless the match ended)."""
    t0 = time.perf_counter()
    home, away = job["colours"]
    row = {
        "match_id": job["match_id"],
        "seed": job["seed"],
        "home_colour": home,
        "away_colour": away,
        "worker": worker_name(),
        "simatch_version": version(),
    }
    analysis = None
    record = job.get("record")
    partial = Path(record + ".partial") if record else None
    try:
        with _Timer(job.get("timeout")):
            scene = scene_from_text(job["scene_text"], job["scene_source"], job["overrides"])
            with Simulation(scene, seed=job["seed"]) as sim:
                live = LiveAnalysis.attach(sim, job["labels"])
                recorder = None
                if partial is not None:
                    partial.parent.mkdir(parents=True, exist_ok=True)
                    partial.unlink(missing_ok=True)  # what a killed run of this same match left
                    recorder = Recorder.for_run(sim, partial, command_line=["simatch", "tournament"])
                try:
                    sim.run()
                except BaseException as exc:
                    if recorder is not None:
                        recorder.close(f"failed: {type(exc).__name__}: {exc}")
                    raise
                out = sim.result()
                if recorder is not None:
                    recorder.close("complete")
                    os.replace(partial, record)
                    row["recording"] = record
                analysis = live.finish(out)
        row.update(_numbers(out, analysis, home, away))
        row["status"] = "ok"
    except MatchTimeout as exc:
        row["status"] = "timeout"
        row["error"] = f"{exc} (stuck at {_where(exc)})"
    except Exception as exc:
        row["status"] = "error"
        where = _where(exc)
        row["error"] = f"{type(exc).__name__}: {exc}" + (f" (at {where})" if where else "")
    row["wall_seconds"] = round(time.perf_counter() - t0, 3)
    row["finished_at"] = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return {"row": row, "analysis": analysis}


def _numbers(out: dict, analysis: dict, home: str, away: str) -> dict:
    result = out.get("result") or {}
    summary = analysis["summary"]
    score = result.get("score") or {home: summary[home]["goals"], away: summary[away]["goals"]}
    row = {
        "home_goals": int(score.get(home, 0)),
        "away_goals": int(score.get(away, 0)),
        "sim_seconds": out["sim_seconds"],
        "state_digest": out["state_digest"],
    }
    winner = result.get("winner")  # the referee's: a shoot-out decides a level score where the scene says so
    if winner is None and row["home_goals"] != row["away_goals"]:
        winner = home if row["home_goals"] > row["away_goals"] else away
    row["winner_colour"] = winner or ""
    for side, team in (("home", home), ("away", away)):
        s = summary[team]
        row[f"{side}_fouls"] = int((result.get("fouls") or {}).get(team, s["fouls"]))
        row[f"{side}_yellow_cards"] = int((result.get("yellow_cards") or {}).get(team, s["yellow_cards"]))
        row[f"{side}_red_cards"] = int((result.get("red_cards") or {}).get(team, s["red_cards"]))
        row[f"{side}_possession"] = s["possession"]
        row[f"{side}_shots"] = s["shots"]
        row[f"{side}_on_target"] = s["on_target"]
        row[f"{side}_strategy_errors"] = s["strategy_errors"]
    return row
