"""A tournament: its teams, scene, seeds and format, the matches they call for, and the loop that plays what
is missing, stores each result as it comes back and makes the standing (docs/tournament.md).

    t = Tournament(parse_entries(["nubot,simple"]), seeds=range(10), out="results")
    with RayPool() as pool:   # or PlainLoop()
        summary = t.play(pool)

Playing is idempotent: the results folder keeps every finished match under its identity (see
`simatch.tournament.schedule`), so calling `play` again — after Ctrl-C, a killed driver, or with more seeds
or teams — plays only the matches that have no result yet.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Iterable
from pathlib import Path

from ..config.loader import load_scene
from ..errors import UsageError
from ..report.page import PLOTLY_FILE, write_plotly_js
from .entries import Entry
from .results import FAILED, REPLAYED, ResultStore
from .schedule import FORMATS, Match, MatchContext, make_format
from .standing import progression, standing

log = logging.getLogger(__name__)

TIMEOUT_MARGIN = 120.0  # [s] added to a match's simulated length for its default wall-clock limit


def match_seconds(spec) -> float:
    """Simulated length of a refereed match of the scene (halves, breaks; a shoot-out counted as 5 min)."""
    m = spec.match
    total = m.halves * m.half_duration + max(0, m.halves - 1) * m.half_time
    return total + (300.0 if m.penalty_shootout else 0.0)


def safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-") or "team"


class Tournament:
    def __init__(
        self,
        entries: list[Entry],
        seeds: Iterable[int],
        out: str | Path,
        scene: str = "msl_5v5",
        overrides: dict | None = None,
        format: str = "round-robin",
        timeout: float | None = None,
        record: str | Path | None = None,
        report: str | Path | None = None,
        retry_failed: bool = False,
    ):
        if format not in FORMATS:
            raise UsageError(f"unknown format {format!r}: choose one of {', '.join(FORMATS)}")
        self.entries = list(entries)
        self.seeds = sorted(set(int(s) for s in seeds))
        if not self.seeds:
            raise UsageError("a tournament needs at least one seed (--seeds N)")
        self.overrides = dict(overrides or {})
        loaded = load_scene(scene, self.overrides)
        spec = loaded.spec
        if len(spec.teams) != 2:
            raise UsageError(f"scene {loaded.name} has {len(spec.teams)} teams: a match needs exactly two colours")
        if spec.judge.kind != "msl_referee":
            raise UsageError(
                f"scene {loaded.name} is judged by {spec.judge.kind!r}: tournament matches need the referee "
                f'(judge.kind = "msl_referee") to give a score'
            )
        self.scene = loaded
        self.colours = tuple(spec.teams)
        self.ctx = MatchContext(loaded.text, loaded.source, self.overrides, self.colours, self.entries)
        self.format = make_format(format, self.ctx, self.seeds)
        self.timeout = timeout if timeout is not None else match_seconds(spec) + TIMEOUT_MARGIN
        if self.timeout <= 0:
            raise UsageError("--timeout must be positive")
        self.store = ResultStore(out)
        self.record = Path(record) if record else None
        self.report = Path(report) if report else None
        self.retry_failed = retry_failed
        self.labels = [e.label for e in self.entries]
        self.problems: list[str] = []

    # --- the matches -------------------------------------------------------------------------------------------
    def stem(self, m: Match) -> str:
        return f"{safe(self.labels[m.home])}_vs_{safe(self.labels[m.away])}_seed{m.seed}_{m.match_id[:10]}"

    def job(self, m: Match) -> dict:
        home, away = self.colours
        overrides = dict(self.overrides)
        overrides.update(self.entries[m.home].overrides(home))
        overrides.update(self.entries[m.away].overrides(away))
        return {
            "match_id": m.match_id,
            "seed": m.seed,
            "scene_text": self.scene.text,
            "scene_source": self.scene.source,
            "overrides": overrides,
            "colours": [home, away],
            "labels": {home: self.labels[m.home], away: self.labels[m.away]},
            "timeout": self.timeout,
            "record": str((self.record / f"{self.stem(m)}.mcap").resolve()) if self.record else None,
        }

    def results(self) -> dict[str, dict]:
        """Rows of matches played so far that count as played (a crashed one, or with --retry-failed any
        failed one, is played again)."""
        rows, problems = self.store.load()
        for text in problems:
            log.warning("a result file cannot be read and its match is played again: %s", text)
        self.problems = problems
        replay = FAILED if self.retry_failed else REPLAYED
        return {mid: r for mid, r in rows.items() if r["status"] not in replay}

    def _labelled(self, m: Match, row: dict) -> dict:
        """A stored row with this tournament's names and schedule (the stored names may be older)."""
        out = dict(row)
        out.update(
            order=m.order,
            stage=m.stage,
            tie=m.tie,
            home=self.labels[m.home],
            away=self.labels[m.away],
            home_strategy=self.entries[m.home].strategy,
            away_strategy=self.entries[m.away].strategy,
        )
        label_of = {self.colours[0]: out["home"], self.colours[1]: out["away"]}
        out["winner"] = label_of.get(out.get("winner_colour") or "", "")
        return out

    # --- playing -----------------------------------------------------------------------------------------------
    def play(self, executor, on_result: Callable[[dict, int, int], None] | None = None) -> dict:
        """Play every match that has no result yet (wave after wave: a knockout round once the one before is
        decided), storing each as it ends. ``on_result(row, done, expected)`` is called after each."""
        self.store.prepare()
        if self.report is not None:
            write_plotly_js(self.report)
        done = self.results()
        while True:
            wave = self.format.wave(done)
            if not wave:
                break
            by_id = {m.match_id: m for m in wave}
            for job, outcome in executor.map(self.job(m) for m in wave):
                m = by_id[job["match_id"]]
                row = self._labelled(m, outcome["row"])
                self.store.add(row, outcome.get("analysis"))
                done[m.match_id] = row
                if self.report is not None and outcome.get("analysis") is not None:
                    self._match_report(m, row, outcome["analysis"])
                if on_result is not None:
                    on_result(row, self.played(done), self.format.expected(done))
        summary = self.finish(done)
        summary["executor"] = getattr(executor, "description", type(executor).__name__)
        return summary

    def played(self, done: dict) -> int:
        return sum(1 for m in self.format.scheduled(done) if m.match_id in done)

    def finish(self, done: dict | None = None) -> dict:
        """The consolidated table, the standing (``standing.json``) and, with a report folder, the reports;
        also after an interruption (with what was played)."""
        if done is None:
            done = self.results()
        scheduled = self.format.scheduled(done)
        rows = [self._labelled(m, done[m.match_id]) for m in scheduled if m.match_id in done]
        table = self.store.write_table(rows)
        summary = self.summary(rows, scheduled, done)
        summary["results"] = str(table)
        if self.report is not None:
            summary["report"] = str(self._tournament_report(summary, rows, scheduled))
        self.store.write_json("standing.json", summary)
        return summary

    def summary(self, rows: list[dict], scheduled: list[Match], done: dict) -> dict:
        out = standing(self.labels, rows)
        played = len(rows)
        failed = sum(1 for r in rows if r["status"] in FAILED)
        remaining = self.format.wave(done)
        out["tournament"] = {
            "format": self.format.name,
            "scene": self.scene.name,
            "scene_source": self.scene.source,
            "overrides": self.overrides,
            "colours": list(self.colours),
            "seeds": self.seeds,
            "teams": [{"name": e.label, "team": e.written, **e.identity()} for e in self.entries],
            "timeout": self.timeout,
            "out": str(self.store.folder),
        }
        out["matches"] = {
            "scheduled": len(scheduled),
            "expected": self.format.expected(done),
            "played": played - failed,
            "failed": failed,
            "missing": len(remaining),
        }
        out["complete"] = not remaining
        out["format_detail"] = self.format.describe(done)
        if self.format.name == "league":
            stages = list(dict.fromkeys(m.stage for m in scheduled))
            out["progression"] = {"matchdays": stages, "places": progression(self.labels, rows, stages)}
        return out

    # --- reports -----------------------------------------------------------------------------------------------
    def _match_report(self, m: Match, row: dict, analysis: dict) -> Path:
        from ..report.match_report import write_match_report

        path = self.report / "matches" / f"{self.stem(m)}.html"
        analysis = dict(analysis, tournament={"index": "../index.html", "stage": m.stage, "match_id": m.match_id})
        return write_match_report(analysis, path, plotly_js=f"../{PLOTLY_FILE}")

    def _tournament_report(self, summary: dict, rows: list[dict], scheduled: list[Match]) -> Path:
        from ..report.tournament_report import write_tournament_report

        write_plotly_js(self.report)
        by_id = {m.match_id: m for m in scheduled}
        for r in rows:
            m = by_id[r["match_id"]]
            page = self.report / "matches" / f"{self.stem(m)}.html"
            if r["status"] == "ok" and not page.exists():
                analysis = self.store.analysis(m.match_id)
                if analysis is not None:
                    self._match_report(m, r, analysis)
            r["report"] = f"matches/{page.name}" if page.exists() else ""
        return write_tournament_report(summary, rows, self.report)
