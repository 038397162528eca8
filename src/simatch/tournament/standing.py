"""The standing of a tournament: points (win 3, draw 1), goal difference, goals, Elo with its interval; the
head-to-head of every two teams and the distribution of their scores. Failed matches count for nobody
(they are listed with their errors)."""

from __future__ import annotations

from collections import Counter

from . import elo

WIN, DRAW = 3, 1


def standing(labels: list[str], rows: list[dict]) -> dict:
    """Everything the table and the tournament report show, from the rows of the played matches."""
    index = {label: i for i, label in enumerate(labels)}
    table = {label: _table_row(label) for label in labels}
    h2h: dict[str, dict[str, dict]] = {a: {} for a in labels}
    scores: dict[str, Counter] = {}
    games = []
    failed = []
    for r in rows:
        home, away = r["home"], r["away"]
        if home not in index or away not in index:
            continue
        if r["status"] != "ok":
            table[home]["failed"] += 1
            table[away]["failed"] += 1
            failed.append({k: r.get(k) for k in ("match_id", "home", "away", "seed", "status", "error", "stage")})
            continue
        hg, ag = int(r["home_goals"]), int(r["away_goals"])
        for me, them, gf, ga, side in ((home, away, hg, ag, "home"), (away, home, ag, hg, "away")):
            _count_match(table[me], r, side, gf, ga)
            h = h2h[me].setdefault(them, dict(played=0, won=0, drawn=0, lost=0, goals_for=0, goals_against=0, points=0))
            _count_head_to_head(h, gf, ga)
        a, b = sorted((home, away), key=index.get)
        ga_, gb_ = (hg, ag) if a == home else (ag, hg)
        scores.setdefault(f"{a} vs {b}", Counter())[f"{ga_}-{gb_}"] += 1
        games.append((index[home], index[away], 1.0 if hg > ag else 0.5 if hg == ag else 0.0, int(r["seed"])))
    rated = elo.ratings(len(labels), games)
    return {
        "standing": _ranked(table, index, rated),
        "head_to_head": h2h,
        "scores": {k: dict(sorted(v.items(), key=lambda kv: (-kv[1], kv[0]))) for k, v in scores.items()},
        "failed": failed,
        "elo_seeds": rated["seeds"],
    }


def _table_row(label: str) -> dict:
    """A team's line of the table before any match (possession summed until `_ranked` averages it)."""
    return dict(
        team=label,
        played=0,
        won=0,
        drawn=0,
        lost=0,
        goals_for=0,
        goals_against=0,
        points=0,
        failed=0,
        shots=0,
        on_target=0,
        possession_sum=0.0,
        possession_n=0,
    )


def _count_match(t: dict, r: dict, side: str, gf: int, ga: int) -> None:
    """Count a played match in the table line ``t`` of the team that played it as ``side`` ("home", "away")."""
    t["played"] += 1
    t["goals_for"] += gf
    t["goals_against"] += ga
    t["shots"] += int(r.get(f"{side}_shots") or 0)
    t["on_target"] += int(r.get(f"{side}_on_target") or 0)
    if r.get(f"{side}_possession") is not None:
        t["possession_sum"] += float(r[f"{side}_possession"])
        t["possession_n"] += 1
    if gf > ga:
        t["won"] += 1
        t["points"] += WIN
    elif gf == ga:
        t["drawn"] += 1
        t["points"] += DRAW
    else:
        t["lost"] += 1


def _count_head_to_head(h: dict, gf: int, ga: int) -> None:
    h["played"] += 1
    h["goals_for"] += gf
    h["goals_against"] += ga
    h["won"] += gf > ga
    h["drawn"] += gf == ga
    h["lost"] += gf < ga
    h["points"] += WIN if gf > ga else DRAW if gf == ga else 0


def _ranked(table: dict[str, dict], index: dict[str, int], rated: dict) -> list[dict]:
    """The table's lines completed (goal difference, mean possession, Elo) and ranked: points, goal
    difference, goals, Elo, then the teams' order."""
    out = []
    for label, t in table.items():
        i = index[label]
        t["goal_difference"] = t["goals_for"] - t["goals_against"]
        t["possession"] = round(t.pop("possession_sum") / t["possession_n"], 4) if t["possession_n"] else None
        t.pop("possession_n")
        t["elo"] = round(float(rated["rating"][i]), 1)
        t["elo_low"] = round(float(rated["low"][i]), 1)
        t["elo_high"] = round(float(rated["high"][i]), 1)
        out.append(t)
    out.sort(key=lambda t: (-t["points"], -t["goal_difference"], -t["goals_for"], -t["elo"], index[t["team"]]))
    for rank, t in enumerate(out, 1):
        t["rank"] = rank
    return out


def progression(labels: list[str], rows: list[dict], stage_order: list[str]) -> dict[str, list[int]]:
    """Each team's place after each stage (a league's matchdays), by points, goal difference, goals."""
    index = {label: i for i, label in enumerate(labels)}
    pts = dict.fromkeys(labels, 0)
    gd = dict.fromkeys(labels, 0)
    gf = dict.fromkeys(labels, 0)
    places: dict[str, list[int]] = {label: [] for label in labels}
    for stage in stage_order:
        for r in rows:
            if r["stage"] != stage or r["status"] != "ok" or r["home"] not in index or r["away"] not in index:
                continue
            hg, ag = int(r["home_goals"]), int(r["away_goals"])
            for me, f, a in ((r["home"], hg, ag), (r["away"], ag, hg)):
                gf[me] += f
                gd[me] += f - a
                pts[me] += WIN if f > a else DRAW if f == a else 0
        order = sorted(labels, key=lambda t: (-pts[t], -gd[t], -gf[t], index[t]))
        for place, t in enumerate(order, 1):
            places[t].append(place)
    return places
