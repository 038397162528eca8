"""What a robot sees of the others, read straight from its perception in plain Python: with a dozen
robots in sight this is cheaper than array code, and every robot does it every control period."""

from __future__ import annotations

#: an obstacle this close to a team-mate's position (each axis) is that team-mate [m]
SAME_ROBOT = 0.1


def opponents(world) -> list[tuple[float, float]]:
    """Positions (team frame) of the robots I see that are not my team-mates."""
    vision = world.vision
    me = world.id
    mates = [(r.x, r.y) for r in vision.robots if r.id != me]
    out = []
    obstacles = vision.obstacles
    for x, y in zip(obstacles.x.tolist(), obstacles.y.tolist()):
        for mx, my in mates:
            if abs(x - mx) <= SAME_ROBOT and abs(y - my) <= SAME_ROBOT:
                break
        else:
            out.append((x, y))
    return out

