"""Plane geometry on plain floats, in the team frame.

A robot handles a handful of points per decision: these helpers work on scalars, from Python (and, the
ones marked as kernels, from compiled kernels).
"""

from __future__ import annotations

import math

from ...compiled import kernel

TWO_PI = 2.0 * math.pi


def wrap(a: float) -> float:
    """The angle ``a`` in [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


#: `wrap` compiled (the same source), for kernels
_wrap = kernel(wrap)


def clamp(v: float, lo: float, hi: float) -> float:
    """``v`` limited to [lo, hi]."""
    return lo if v < lo else hi if v > hi else v


#: `clamp` compiled (the same source), for kernels
_clamp = kernel(clamp)


def dist(ax: float, ay: float, bx: float, by: float) -> float:
    return math.hypot(bx - ax, by - ay)


def unit(dx: float, dy: float) -> tuple[float, float]:
    n = math.hypot(dx, dy)
    if n < 1e-12:
        return (1.0, 0.0)
    return (dx / n, dy / n)


def segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> tuple[float, float]:
    """(distance from P to segment AB, position of the foot along AB in [0, 1])."""
    dx, dy = bx - ax, by - ay
    ll = dx * dx + dy * dy
    if ll < 1e-12:
        return math.hypot(px - ax, py - ay), 0.0
    s = ((px - ax) * dx + (py - ay) * dy) / ll
    s = 0.0 if s < 0.0 else 1.0 if s > 1.0 else s
    return math.hypot(px - ax - s * dx, py - ay - s * dy), s


@kernel
def box_exit(ox: float, oy: float, ux: float, uy: float, x0: float, x1: float, half_w: float) -> float:
    """Along the ray O + s u from a point O inside the box [x0, x1] x [-half_w, half_w], the s at which
    the ray leaves the box (inf if it never does). (Compiled, for the compiled points as for Python's
    callers; Python's min and max, as they take them.)"""
    s = math.inf
    if ux > 1e-12:
        s = min(s, (x1 - ox) / ux)
    elif ux < -1e-12:
        s = min(s, (x0 - ox) / ux)
    if uy > 1e-12:
        s = min(s, (half_w - oy) / uy)
    elif uy < -1e-12:
        s = min(s, (-half_w - oy) / uy)
    return max(0.0, s)


@kernel
def push_out_of_box(x: float, y: float, x0: float, x1: float, half_w: float) -> tuple[float, float]:
    """The nearest point outside the box [x0, x1] x [-half_w, half_w] (the point itself if outside).
    (Compiled, for the compiled motion; on equal distances the faces are taken as ``min`` of the tuples
    (distance, x, y) would take them.)"""
    if not (x0 < x < x1 and -half_w < y < half_w):
        return x, y
    # distances to the faces we may leave through: (x - x0, x0, y), (x1 - x, x1, y), (half_w - y, x, half_w),
    # (y + half_w, x, -half_w)
    best_d, best_x, best_y = x - x0, x0, y
    for j in range(1, 4):
        if j == 1:
            d, nx, ny = x1 - x, x1, y
        elif j == 2:
            d, nx, ny = half_w - y, x, half_w
        else:
            d, nx, ny = y + half_w, x, -half_w
        if d < best_d or (d == best_d and (nx < best_x or (nx == best_x and ny < best_y))):
            best_d, best_x, best_y = d, nx, ny
    return best_x, best_y


def time_to_cover(d: float, v0: float, vmax: float, acc: float) -> float:
    """Seconds to cover distance ``d`` starting at speed ``v0`` (towards it), speeding up at ``acc`` to
    ``vmax``."""
    # (min(max(v0, 0.0), vmax), inline: Python's max keeps v0 unless 0.0 > v0, min keeps it unless vmax < v0)
    v0 = 0.0 if 0.0 > v0 else v0
    v0 = vmax if vmax < v0 else v0
    d_acc = (vmax * vmax - v0 * v0) / (2.0 * acc)
    if d <= d_acc:
        return (math.sqrt(v0 * v0 + 2.0 * acc * d) - v0) / acc
    return (vmax - v0) / acc + (d - d_acc) / vmax


@kernel
def segment_hits_box(ax: float, ay: float, bx: float, by: float, x0: float, x1: float, half_w: float) -> bool:
    """Whether the segment AB passes through the open box [x0, x1] x [-half_w, half_w] (Liang-Barsky).
    (Compiled, for the compiled motion.)"""
    t0, t1 = 0.0, 1.0
    dx, dy = bx - ax, by - ay
    for j in range(4):
        if j == 0:
            p, q = -dx, ax - x0
        elif j == 1:
            p, q = dx, x1 - ax
        elif j == 2:
            p, q = -dy, ay + half_w
        else:
            p, q = dy, half_w - ay
        if abs(p) < 1e-12:
            if q <= 0.0:
                return False
            continue
        r = q / p
        if p < 0.0:
            t0 = max(t0, r)
        else:
            t1 = min(t1, r)
        if t0 >= t1:
            return False
    return True
