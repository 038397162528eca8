"""Which matches a tournament plays: round robin, league (matchdays) and knockout.

Every pairing of two entries is played over the seeds with both colours: for each seed, A on the scene's
first colour against B on the second, and B against A. A match is identified by what decides it — the
scene (its text and overrides), the two teams' strategies and parameters on their colours, and the seed —
so the same match in another run of the command, or in a tournament with more seeds or more teams, is the
same row of the results and is never played twice.

* ``round-robin``: every pairing, seed after seed (after seed 0 every pairing has played once each way).
* ``league``: the same matches in matchdays: each matchday every team plays one opponent (the circle method;
  a team rests on a matchday when the count is odd), a lap of matchdays per seed; the table is kept after
  each matchday.
* ``knockout``: a single-elimination bracket in the order the teams are given (the first is the top seed;
  byes go to the top seeds when the count is no power of two). A tie is every seed both ways; the winner
  has more points, then a better goal difference, then more goals; still level, deciders are played with the
  next seeds (colours alternating) until one is won, at most `MAX_DECIDERS`; then the higher seed goes on.
  A round is scheduled once the round before it is decided.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

from .entries import Entry, canonical

FORMATS = ("round-robin", "league", "knockout")
MAX_DECIDERS = 10
ROUND_NAMES = {1: "final", 2: "semi-final", 4: "quarter-final"}


@dataclass(frozen=True)
class Match:
    match_id: str
    home: int  # entry index on the scene's first colour
    away: int  # entry index on the second colour
    seed: int
    stage: str  # "round robin", "matchday 3", "semi-final", "semi-final decider"
    order: int  # position in the schedule (rows and reports follow it)
    tie: str = ""  # knockout: the tie this match belongs to


@dataclass
class MatchContext:
    """What every match of a tournament shares: the scene and its colours."""

    scene_text: str
    scene_source: str
    overrides: dict
    colours: tuple[str, str]
    entries: list[Entry]
    scene_key: str = field(init=False)

    def __post_init__(self) -> None:
        self.scene_key = hashlib.sha256(
            canonical({"text": self.scene_text, "overrides": self.overrides}).encode()
        ).hexdigest()

    def match_id(self, home: int, away: int, seed: int) -> str:
        ident = {
            "scene": self.scene_key,
            "colours": list(self.colours),
            "home": self.entries[home].identity(),
            "away": self.entries[away].identity(),
            "seed": int(seed),
        }
        return hashlib.sha256(canonical(ident).encode()).hexdigest()[:20]

    def match(self, home: int, away: int, seed: int, stage: str, order: int, tie: str = "") -> Match:
        return Match(self.match_id(home, away, seed), home, away, int(seed), stage, order, tie)


def pairings(n: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(n) for j in range(i + 1, n)]


def matchdays(n: int) -> list[list[tuple[int, int]]]:
    """The circle method: n-1 matchdays (n even; a rest for one team each matchday when n is odd)."""
    teams: list[int | None] = list(range(n)) + ([None] if n % 2 else [])
    m = len(teams)
    days = []
    for _ in range(m - 1):
        day = []
        for k in range(m // 2):
            a, b = teams[k], teams[m - 1 - k]
            if a is not None and b is not None:
                day.append((min(a, b), max(a, b)))
        days.append(day)
        teams = [teams[0], teams[-1], *teams[1:-1]]
    return days


class RoundRobin:
    name = "round-robin"

    def __init__(self, ctx: MatchContext, seeds: list[int]):
        self.ctx, self.seeds = ctx, seeds
        self.matches: list[Match] = []
        order = 0
        for seed in seeds:
            for i, j in pairings(len(ctx.entries)):
                for home, away in ((i, j), (j, i)):
                    self.matches.append(ctx.match(home, away, seed, "round robin", order))
                    order += 1

    def wave(self, results: dict) -> list[Match]:
        """The matches that can be played now and have no result yet ([] when the tournament is over)."""
        return [m for m in self.matches if m.match_id not in results]

    def scheduled(self, results: dict) -> list[Match]:
        """Every match known so far, in order."""
        return list(self.matches)

    def expected(self, results: dict) -> int:
        return len(self.matches)

    def describe(self, results: dict) -> dict:
        return {"format": self.name}


class League(RoundRobin):
    name = "league"

    def __init__(self, ctx: MatchContext, seeds: list[int]):
        self.ctx, self.seeds = ctx, seeds
        self.matches = []
        self.days = matchdays(len(ctx.entries))
        order = 0
        number = 0
        for seed in seeds:
            for day in self.days:
                number += 1
                for i, j in day:
                    for home, away in ((i, j), (j, i)):
                        self.matches.append(ctx.match(home, away, seed, f"matchday {number}", order))
                        order += 1

    def describe(self, results: dict) -> dict:
        return {"format": self.name, "matchdays": len(self.seeds) * len(self.days)}


@dataclass
class Tie:
    key: str
    round: str
    a: int | None  # the higher seed (None: not known yet)
    b: int | None
    winner: int | None = None
    how: str = ""
    matches: list[Match] = field(default_factory=list)


class Knockout:
    name = "knockout"

    def __init__(self, ctx: MatchContext, seeds: list[int]):
        self.ctx, self.seeds = ctx, seeds
        n = len(ctx.entries)
        size = 1
        while size < n:
            size *= 2
        self.size = size
        order = [1]
        while len(order) < size:
            total = 2 * len(order) + 1
            order = [x for s in order for x in (s, total - s)]
        self.first_round = [(order[k] - 1, order[k + 1] - 1) for k in range(0, size, 2)]

    @staticmethod
    def round_name(ties: int) -> str:
        return ROUND_NAMES.get(ties, f"round of {2 * ties}")

    def bracket(self, results: dict) -> list[list[Tie]]:
        """The rounds as far as the results decide them."""
        n = len(self.ctx.entries)
        rounds: list[list[Tie]] = []
        current: list[tuple[int | None, int | None]] = [
            (a if a < n else None, b if b < n else None) for a, b in self.first_round
        ]
        counter = 0
        while current:
            name = self.round_name(len(current))
            ties = []
            for k, (a, b) in enumerate(current):
                tie = Tie(f"{name} {k + 1}", name, a, b)
                if a is None or b is None:
                    tie.winner = a if b is None else b
                    tie.how = "bye" if tie.winner is not None else ""
                else:
                    counter = self._play(tie, results, counter)
                ties.append(tie)
            rounds.append(ties)
            if len(current) == 1 or any(t.winner is None and (t.a is not None or t.b is not None) for t in ties):
                break
            current = [(ties[k].winner, ties[k + 1].winner) for k in range(0, len(ties), 2)]
        return rounds

    def _play(self, tie: Tie, results: dict, counter: int) -> int:
        ctx = self.ctx
        a, b = tie.a, tie.b
        base = counter * 1000
        k = 0
        for seed in self.seeds:
            for home, away in ((a, b), (b, a)):
                tie.matches.append(ctx.match(home, away, seed, tie.round, base + k, tie.key))
                k += 1
        counter += 1
        if any(m.match_id not in results for m in tie.matches):
            return counter
        score = _aggregate(tie.matches, results, a, b)
        if score[a] != score[b]:
            tie.winner = a if score[a] > score[b] else b
            tie.how = "on aggregate"
            return counter
        extra = max(self.seeds, default=-1) + 1
        for d in range(MAX_DECIDERS):
            home, away = (a, b) if d % 2 == 0 else (b, a)
            m = ctx.match(home, away, extra + d, f"{tie.round} decider", base + k, tie.key)
            k += 1
            tie.matches.append(m)
            row = results.get(m.match_id)
            if row is None:
                return counter
            if row.get("status") == "ok" and row["home_goals"] != row["away_goals"]:
                tie.winner = home if row["home_goals"] > row["away_goals"] else away
                tie.how = f"won decider (seed {m.seed})"
                return counter
        tie.winner = a
        tie.how = "level after every decider: the higher seed goes on"
        return counter

    def wave(self, results: dict) -> list[Match]:
        return [m for m in self.scheduled(results) if m.match_id not in results]

    def scheduled(self, results: dict) -> list[Match]:
        return [m for rnd in self.bracket(results) for tie in rnd for m in tie.matches]

    def expected(self, results: dict) -> int:
        """Matches known so far plus those of the rounds to come, without deciders."""
        known = len(self.scheduled(results))
        rounds = self.bracket(results)
        ties_left = 0
        ties = len(rounds[-1]) if rounds else 0
        while ties > 1:
            ties //= 2
            ties_left += ties
        return known + ties_left * 2 * len(self.seeds)

    def describe(self, results: dict) -> dict:
        labels = [e.label for e in self.ctx.entries]
        rounds = []
        for rnd in self.bracket(results):
            rounds.append(
                [
                    {
                        "tie": t.key,
                        "round": t.round,
                        "a": labels[t.a] if t.a is not None else None,
                        "b": labels[t.b] if t.b is not None else None,
                        "winner": labels[t.winner] if t.winner is not None else None,
                        "how": t.how,
                        "score": _aggregate_text(t, results, labels),
                    }
                    for t in rnd
                ]
            )
        final = rounds[-1][0] if rounds and len(rounds[-1]) == 1 else None
        champion = final["winner"] if final else None
        return {"format": self.name, "rounds": rounds, "champion": champion}


def _aggregate(matches: list[Match], results: dict, a: int, b: int) -> dict:
    """Points, then goal difference, then goals of ``a`` and ``b`` over the tie's played matches (a tuple per
    team, compared in that order)."""
    pts = {a: 0, b: 0}
    gd = {a: 0, b: 0}
    gf = {a: 0, b: 0}
    for m in matches:
        row = results.get(m.match_id)
        if row is None or row.get("status") != "ok" or m.seed < 0:
            continue
        hg, ag = row["home_goals"], row["away_goals"]
        gf[m.home] += hg
        gf[m.away] += ag
        gd[m.home] += hg - ag
        gd[m.away] += ag - hg
        if hg > ag:
            pts[m.home] += 3
        elif hg < ag:
            pts[m.away] += 3
        else:
            pts[m.home] += 1
            pts[m.away] += 1
    return {t: (pts[t], gd[t], gf[t]) for t in (a, b)}


def _aggregate_text(tie: Tie, results: dict, labels: list[str]) -> str:
    if tie.a is None or tie.b is None:
        return ""
    regular = [m for m in tie.matches if "decider" not in m.stage]
    s = _aggregate(regular, results, tie.a, tie.b)
    return f"{s[tie.a][0]}-{s[tie.b][0]} pts, goals {s[tie.a][2]}-{s[tie.b][2]}"


def make_format(name: str, ctx: MatchContext, seeds: list[int]):
    return {"round-robin": RoundRobin, "league": League, "knockout": Knockout}[name](ctx, seeds)
