"""The bridge's RViz markers (``/simatch/markers``): the field's lines and goals, and each robot and the ball, in
``map``: what a ROS user sees of a match without any model of its own."""

from __future__ import annotations

from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from ..field import arc_points
from . import names
from .convert import WorldPose, quaternion_of_yaw

ROBOT_RADIUS = 0.25  # [m] the drawn footprint (the shipped models')
ROBOT_HEIGHT = 0.8
BALL_RADIUS = 0.11

_COLORS = {
    "cyan": (0.0, 0.8, 0.9),
    "magenta": (0.9, 0.1, 0.7),
    "blue": (0.1, 0.3, 0.9),
    "yellow": (0.95, 0.85, 0.1),
    "red": (0.9, 0.1, 0.1),
    "green": (0.1, 0.8, 0.2),
}


def _color(rgb: tuple[float, float, float], a: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=float(rgb[0]), g=float(rgb[1]), b=float(rgb[2]), a=float(a))


def field(spec) -> list:
    """The field's markings (one LINE_LIST) and the goals, in ``map``: drawn with every MarkerArray."""
    geo = spec.world.geometry()
    lines = Marker()
    lines.header.frame_id = names.MAP
    lines.ns, lines.id, lines.type, lines.action = "field", 0, Marker.LINE_LIST, Marker.ADD
    lines.scale.x = float(geo.line_width)
    lines.color = _color((1.0, 1.0, 1.0))
    lines.pose.orientation.w = 1.0
    for item in geo.lines():
        if item["kind"] == "polyline":
            pts = item["points"]
            segs = zip(pts[:-1], pts[1:])
        elif item["kind"] == "arc":
            arc = arc_points(item, 48)
            segs = zip(arc[:-1], arc[1:])
        else:
            continue
        for (x0, y0), (x1, y1) in segs:
            lines.points.append(Point(x=float(x0), y=float(y0), z=0.01))
            lines.points.append(Point(x=float(x1), y=float(y1), z=0.01))
    out = [lines]
    spec_world = spec.world
    L = geo.half_length
    for k, side in enumerate((-1, 1)):
        goal = Marker()
        goal.header.frame_id = names.MAP
        goal.ns, goal.id, goal.type, goal.action = "goals", k, Marker.CUBE, Marker.ADD
        depth = float(getattr(spec_world, "goal_depth", 0.6))
        goal.pose.position.x = side * (L + depth / 2)
        goal.pose.position.z = 0.5
        goal.pose.orientation.w = 1.0
        goal.scale.x, goal.scale.y, goal.scale.z = depth, float(getattr(spec_world, "goal_width", 2.4)), 1.0
        goal.color = _color((0.9, 0.9, 0.9), 0.4)
        out.append(goal)
    return out


def markers(spec, field_markers: list, stamp, poses: dict[str, WorldPose]) -> MarkerArray:
    """The field's markers (from `field`, built once) and, for each pose, the ball or a robot in its team's
    colour: a cylinder, an arrow on the kicker's side and its name, all stamped ``stamp``."""
    out = MarkerArray()
    for m in field_markers:
        m.header.stamp = stamp
        out.markers.append(m)
    for name, p in sorted(poses.items()):
        m = Marker()
        m.header.stamp = stamp
        m.header.frame_id = names.MAP
        m.action = Marker.ADD
        m.pose.orientation.w = 1.0
        if name == names.BALL:
            m.ns, m.id, m.type = "ball", 0, Marker.SPHERE
            m.pose.position.x, m.pose.position.y = p.x, p.y
            m.pose.position.z = p.z
            m.scale.x = m.scale.y = m.scale.z = 2 * BALL_RADIUS
            m.color = _color((1.0, 0.5, 0.0))
            out.markers.append(m)
            continue
        team, _, rid = name.partition("/")
        rgb = _COLORS.get(spec.team_color(team), (0.7, 0.7, 0.7))
        m.ns, m.id, m.type = f"robots/{team}", int(rid), Marker.CYLINDER
        m.pose.position.x, m.pose.position.y, m.pose.position.z = p.x, p.y, p.z + ROBOT_HEIGHT / 2
        qx, qy, qz, qw = quaternion_of_yaw(p.yaw)
        m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = qx, qy, qz, qw
        m.scale.x = m.scale.y = 2 * ROBOT_RADIUS
        m.scale.z = ROBOT_HEIGHT
        m.color = _color(rgb)
        out.markers.append(m)
        head = Marker()  # the kicker's side
        head.header = m.header
        head.ns, head.id, head.type, head.action = f"heading/{team}", int(rid), Marker.ARROW, Marker.ADD
        head.pose = m.pose
        head.scale.x, head.scale.y, head.scale.z = ROBOT_RADIUS * 1.6, 0.08, 0.08
        head.color = _color((1.0, 1.0, 1.0))
        out.markers.append(head)
        label = Marker()
        label.header = m.header
        label.ns, label.id, label.type, label.action = (
            f"labels/{team}",
            int(rid),
            Marker.TEXT_VIEW_FACING,
            Marker.ADD,
        )
        label.pose.position.x, label.pose.position.y, label.pose.position.z = p.x, p.y, p.z + ROBOT_HEIGHT + 0.3
        label.pose.orientation.w = 1.0
        label.scale.z = 0.4
        label.color = _color((1.0, 1.0, 1.0))
        label.text = name
        out.markers.append(label)
    return out
