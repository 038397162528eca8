"""What a robot sees of the others, read straight from its perception in plain Python (a dozen robots in
sight, every control period)."""

from __future__ import annotations

#: an obstacle within this distance of where a team-mate says it is may be that team-mate [m]; two robots'
#: centres are never nearer than a robot's width (0.5 m), so noise up to a few centimetres is told apart
SAME_ROBOT = 0.4


def opponents(world) -> list[tuple[float, float]]:
    """Positions (team frame) of the robots I see that are not my team-mates.

    With exact perception a team-mate is seen exactly where it says it is, which a set lookup finds.
    Otherwise each team-mate claims the obstacle nearest to where it is (nearest pairs first, each obstacle
    claimed once), so noisy positions and missed obstacles do not turn a team-mate into an opponent."""
    vision = world.vision
    me = world.id
    obstacles = vision.obstacles
    seen = list(zip(obstacles.x.tolist(), obstacles.y.tolist()))
    mates = [(r.x, r.y) for r in vision.robots if r.id != me]
    exact = set(mates)
    rest = [p for p in seen if p not in exact]
    if len(seen) - len(rest) == len(mates):
        return rest
    limit = SAME_ROBOT * SAME_ROBOT
    pairs = []
    for j, (mx, my) in enumerate(mates):
        for i, (x, y) in enumerate(seen):
            dx, dy = x - mx, y - my
            if abs(dx) < SAME_ROBOT and abs(dy) < SAME_ROBOT and (d2 := dx * dx + dy * dy) < limit:
                pairs.append((d2, i, j))
    pairs.sort()
    claimed, matched = set(), set()
    for _, i, j in pairs:
        if i not in claimed and j not in matched:
            claimed.add(i)
            matched.add(j)
    return [p for i, p in enumerate(seen) if i not in claimed]
