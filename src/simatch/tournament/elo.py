"""Elo ratings of a tournament's teams, with a confidence interval from the seeds.

The ratings are the maximum-likelihood fit of the Elo model to every played match at once (a win scores 1,
a draw 1/2, a loss 0; the expected score of A against B is 1 / (1 + 10^((R_B - R_A) / 400))), which, unlike
Elo's running updates, does not depend on the order the matches finished in. One virtual draw between every
two teams that met keeps a team that won (or lost) everything at a finite rating, as BayesElo's prior does.
The mean rating is 1500.

The interval: the seeds are the tournament's random draws, so the matches are resampled seed by seed (all
matches of a seed together, with replacement; `BOOTSTRAP` resamples from a fixed generator, so the same
results give the same interval) and the fit repeated; the 2.5 and 97.5 percentiles of each team's rating
are its 95 % interval. Where every seed gave the same results (a strategy that beats another in every
seed, as deterministic teams often do) resampling shows no spread at all, though forty wins say only that
the winner is much stronger, not how much: so the interval is widened to at least the likelihood's own
(the fit's curvature, ±1.96 standard errors, as BayesElo gives), which is wide exactly where the results
say little.
"""

from __future__ import annotations

import numpy as np

BOOTSTRAP = 1000
MEAN = 1500.0
PRIOR_DRAWS = 1.0
SCALE = 400.0
#: the normal distribution's 97.5 % quantile
Z95 = 1.959963984540054


def _tables(n: int, games: list[tuple[int, int, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Each pair's summed score and game count, the virtual draws included."""
    score = np.zeros((n, n))
    count = np.zeros((n, n))
    for a, b, s in games:
        score[a, b] += s
        score[b, a] += 1.0 - s
        count[a, b] += 1.0
        count[b, a] += 1.0
    met = count > 0
    score += 0.5 * PRIOR_DRAWS * met
    count += PRIOR_DRAWS * met
    return score, count


def _information(theta: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Minus the log-likelihood's Hessian at the log-strengths ``theta``: positive semi-definite, with the
    ones (a shift of every rating) in its kernel."""
    p = 1.0 / (1.0 + np.exp(theta[None, :] - theta[:, None]))  # P(i beats j)
    q = count * p * (1.0 - p)
    return np.diag(q.sum(axis=1)) - q


def fit(n: int, games: list[tuple[int, int, float]], iterations: int = 60) -> np.ndarray:
    """Ratings of ``n`` teams from ``(a, b, score of a)`` games: Newton's method on the log-likelihood of the
    logistic (Bradley-Terry) model, which the virtual draws make strictly concave."""
    score, count = _tables(n, games)
    played = count.sum(axis=1) > 0
    theta = np.zeros(n)  # natural log-strengths
    idx = np.flatnonzero(played)
    for _ in range(iterations if len(idx) > 1 else 0):
        p = 1.0 / (1.0 + np.exp(theta[None, :] - theta[:, None]))  # P(i beats j)
        grad = (score - count * p).sum(axis=1)
        sub = _information(theta, count)[np.ix_(idx, idx)] + 1.0 / len(idx)  # fixes the mean (the kernel)
        step = np.linalg.lstsq(sub, grad[idx], rcond=None)[0]  # least squares: teams in groups that never met
        theta[idx] += step
        theta[idx] -= theta[idx].mean()
        if np.max(np.abs(step)) < 1e-10:
            break
    return MEAN + theta * SCALE / np.log(10.0)


def standard_errors(n: int, games: list[tuple[int, int, float]], rating: np.ndarray) -> np.ndarray:
    """Each rating's standard error from the fit's curvature at ``rating`` (the mean held at 1500): the
    inverse of the information on the ratings that sum to the mean; 0 for a team that played nothing."""
    _, count = _tables(n, games)
    idx = np.flatnonzero(count.sum(axis=1) > 0)
    sd = np.zeros(n)
    if len(idx) < 2:
        return sd
    theta = (rating - MEAN) * np.log(10.0) / SCALE
    info = _information(theta, count)[np.ix_(idx, idx)]
    cov = np.linalg.pinv(info)  # the pseudo-inverse: the covariance of mean-zero log-strengths
    sd[idx] = np.sqrt(np.clip(np.diag(cov), 0.0, None)) * SCALE / np.log(10.0)
    return sd


def ratings(n: int, games: list[tuple[int, int, float, int]], samples: int = BOOTSTRAP) -> dict:
    """Ratings and their 95 % interval from ``(a, b, score of a, seed)`` games."""
    plain = [(a, b, s) for a, b, s, _ in games]
    best = fit(n, plain)
    seeds = sorted({seed for *_, seed in games})
    by_seed = {seed: [(a, b, s) for a, b, s, sd in games if sd == seed] for seed in seeds}
    low = high = best.copy()
    if len(seeds) >= 2:
        rng = np.random.default_rng(0)
        draws = np.empty((samples, n))
        for k in range(samples):
            pick = rng.choice(len(seeds), size=len(seeds), replace=True)
            draws[k] = fit(n, [g for i in pick for g in by_seed[seeds[i]]])
        low = np.percentile(draws, 2.5, axis=0)
        high = np.percentile(draws, 97.5, axis=0)
    sd = standard_errors(n, plain, best)
    low = np.minimum(low, best - Z95 * sd)
    high = np.maximum(high, best + Z95 * sd)
    return {"rating": best, "low": low, "high": high, "seeds": len(seeds)}
