"""Building the MuJoCo world from a scene, in code (MjSpec): floor, boards, goals, ball and robots.

Everything the simulator later touches by index (joint addresses, actuators, equality constraints) is
resolved here once and kept in `WorldIndex`, so that no name lookup happens while stepping.

Collision groups (contype/conaffinity bits) keep every contact pair meaningful and cheap:

    FLOOR   the ground plane; only the ball touches it (robots are planar: they never tip)
    HULL    the robots' sphere hulls; they touch each other, goals and boards (frictionless between robots)
    BALL    the ball
    MOUTH   the robots' ball colliders (a capsule whose front is the mouth); only the ball touches them
    STATIC  goal frames, nets, boards, obstacles and a ceiling; ball, hulls and drones touch them
    AIR     aerial robots' frames (`simatch.sim.airframe`); they touch the floor, statics, hulls, the ball and
            each other
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from ..config.schema import Scene
from ..field import FieldGeometry, Obstacle
from ..robots import RobotModel, model_class
from ..robots.body import add_freeze_weld, add_ground_robot
from .airframe import AerialIndex, add_airframe, aerial_index

FLOOR, HULL, BALL, MOUTH, STATIC, AIR = 1, 2, 4, 8, 16, 32

BALL_NAME = "ball"


@dataclass
class RobotEntry:
    name: str  # "cyan/2"
    team: str
    rid: int
    model: RobotModel
    start: tuple[float, float, float]


@dataclass
class WorldIndex:
    """Addresses into MjModel/MjData, resolved once.

    Robots are indexed ground robots first (in the scene's order), then aerial ones: the per-robot arrays
    of planar bases below (``robot_qpos`` ... ``freeze_eq``) have one row per ground robot, and ``aerial``
    holds the aerial robots' addresses (None in a world without them)."""

    robots: list[RobotEntry]
    robot_body: np.ndarray  # (N,) body ids
    robot_qpos: np.ndarray  # (N, 3) qpos addresses of x, y, yaw
    robot_qvel: np.ndarray  # (N, 3) dof addresses of vx, vy, w (world frame)
    robot_ctrl: np.ndarray  # (N, 3) actuator ids of the body-frame velocity servo
    robot_act: np.ndarray  # (N, 3) their activation addresses (the servo set points)
    robot_hull_geom: np.ndarray  # (N,)
    robot_mouth_geom: np.ndarray  # (N,)
    dribble_eq: np.ndarray  # (N,) connect constraint robot-ball (inactive)
    freeze_eq: np.ndarray  # (N,) weld robot-world (inactive)
    ball_body: int
    ball_qpos: int  # 7 numbers: x y z qw qx qy qz
    ball_qvel: int  # 6 numbers: vx vy vz wx wy wz
    ball_geom: int
    static_geoms: np.ndarray
    robot_of_geom: dict[int, int] = field(default_factory=dict)  # geom id -> robot index
    aerial: AerialIndex | None = None
    obstacle_geoms: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))


#: contact of the ball with robots, goals and boards: a stiff spring-damper that returns about a third of
#: the impact speed (damping ratio 0.3; a lower one is unstable at 200 Hz)
BALL_BODY_SOLREF = [0.02, 0.3]


def add_obstacle(static_body, static_geom, ob: Obstacle) -> str:
    """A static obstacle of the world's description as a body of its own (its geom's name returned)."""
    body = static_body(ob.name)
    if ob.shape == "cylinder":
        static_geom(
            body,
            ob.name,
            (ob.x, ob.y, ob.height / 2),
            (ob.radius, ob.height / 2, 0.0),
            kind=mujoco.mjtGeom.mjGEOM_CYLINDER,
        )
    else:
        g = static_geom(body, ob.name, (ob.x, ob.y, ob.height / 2), (ob.half_x, ob.half_y, ob.height / 2))
        g.quat = [math.cos(ob.yaw / 2), 0.0, 0.0, math.sin(ob.yaw / 2)]
    return ob.name


class StaticParts:
    """The world's static parts (boards, goals, obstacles, a ceiling): each a body of its own, so that the
    broad phase pairs a robot or the ball only with the parts near it (geoms of the world body share one huge
    bounding box). Every geom added is kept in ``geoms``."""

    def __init__(self, spec: mujoco.MjSpec):
        self.worldbody = spec.worldbody
        self.geoms: list = []

    def body(self, name: str):
        return self.worldbody.add_body(name=name)

    def box(self, body, name: str, center, half_sizes, damped: bool = False, kind=mujoco.mjtGeom.mjGEOM_BOX):
        """A static geom (a box unless ``kind`` says otherwise); ``damped``: a net that swallows the ball."""
        g = body.add_geom(
            name=name,
            type=kind,
            pos=list(center),
            size=list(half_sizes),
            contype=STATIC,
            conaffinity=0,
            condim=3,
            friction=[0.3, 0.005, 0.0001],
        )
        if damped:
            # nets swallow the ball: an overdamped contact, and no friction (with the ball's own friction a
            # spinning ball would climb the net and roll back out; priority makes the net's friction count)
            g.solref = [0.02, 2.0]
            g.priority = 1
            g.friction = [0.0, 0.005, 0.0001]
        else:
            g.solref = BALL_BODY_SOLREF
        self.geoms.append(g)
        return g


def build_world(scene: Scene) -> tuple[mujoco.MjModel, mujoco.MjData, WorldIndex, FieldGeometry]:
    """The MuJoCo model and data of ``scene``, where its parts lie (`WorldIndex`), and its field."""
    spec = _new_spec(scene)
    geo = scene.world.geometry()
    add_floor(spec, geo)
    statics = StaticParts(spec)
    if geo.walls:
        add_boards(statics, geo)
    if geo.goals:
        for side, tag in ((-1, "cyan"), (1, "magenta")):
            add_goal(statics, geo, side, tag)
    obstacle_names = [add_obstacle(statics.body, statics.box, ob) for ob in geo.obstacles]
    if geo.ceiling is not None:
        add_ceiling(statics, geo)
    add_ball(spec, scene)
    ground, flying = robot_entries(scene)
    for entry in ground:
        add_robot(spec, entry, scene)
    for entry in flying:
        add_airframe(spec, entry, AIR, FLOOR | HULL | BALL | STATIC | AIR)
    model = spec.compile()
    data = mujoco.MjData(model)
    index = world_index(model, data, ground, flying, statics.geoms, obstacle_names, scene.physics.gravity)
    for i, r in enumerate(ground):
        data.qpos[index.robot_qpos[i]] = r.start
    mujoco.mj_forward(model, data)
    return model, data, index, geo


def _new_spec(scene: Scene) -> mujoco.MjSpec:
    """An empty world with the scene's physics options."""
    spec = mujoco.MjSpec()
    spec.modelname = scene.name
    opt = spec.option
    opt.timestep = scene.physics.timestep
    opt.gravity = [0.0, 0.0, -scene.physics.gravity]
    opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    # elliptic friction cones: with pyramidal ones the rolling-friction rows of the ball's floor contact
    # make a rolling ball hop and slip; elliptic cones roll it cleanly
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.iterations = scene.physics.solver_iterations
    opt.tolerance = scene.physics.solver_tolerance
    # the mid-phase tree pays off only with many primitives per body (ours have a handful), and no joint has
    # damping for Euler to treat implicitly: both off, with the same trajectories
    opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MIDPHASE | mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    return spec


def _half_extent(geo: FieldGeometry) -> tuple[float, float]:
    """Half the length and width of the world inside the boards (the field and its margin) [m]."""
    return geo.half_length + geo.margin, geo.half_width + geo.margin


def add_floor(spec: mujoco.MjSpec, geo: FieldGeometry) -> None:
    """The ground plane, two metres beyond the boards; only the ball touches it (robots are planar)."""
    half_x, half_y = _half_extent(geo)
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[half_x + 2.0, half_y + 2.0, 0.1],
        contype=FLOOR,
        conaffinity=0,
        condim=3,
    )


def add_boards(statics: StaticParts, geo: FieldGeometry) -> None:
    """Four boards around the field and its margin."""
    half_x, half_y = _half_extent(geo)
    t, h = 0.05, geo.wall_height
    for name, center, size in (
        ("board_+x", (half_x + t, 0, h / 2), (t, half_y + 2 * t, h / 2)),
        ("board_-x", (-half_x - t, 0, h / 2), (t, half_y + 2 * t, h / 2)),
        ("board_+y", (0, half_y + t, h / 2), (half_x, t, h / 2)),
        ("board_-y", (0, -half_y - t, h / 2), (half_x, t, h / 2)),
    ):
        statics.box(statics.body(name), name, center, size)


def add_goal(statics: StaticParts, geo: FieldGeometry, side: int, tag: str) -> None:
    """The goal behind the line at x = ``side`` * half length: two posts and a crossbar that stop the ball,
    and a net (sides, back, top) that swallows it."""
    p, gw, gh, gd = geo.goal_post_size, geo.goal_width, geo.goal_height, geo.goal_depth
    net = 0.01
    body = statics.body(f"goal_{tag}")
    x_line = side * geo.half_length
    x_post = x_line + side * p / 2
    for sy, ytag in ((1, "left"), (-1, "right")):
        statics.box(
            body,
            f"goal_{tag}_post_{ytag}",
            (x_post, sy * (gw / 2 + p / 2), (gh + p) / 2),
            (p / 2, p / 2, (gh + p) / 2),
        )
        statics.box(
            body,
            f"goal_{tag}_net_{ytag}",
            (x_line + side * gd / 2, sy * (gw / 2 + p + net), gh / 2),
            (gd / 2, net, gh / 2),
            damped=True,
        )
    statics.box(body, f"goal_{tag}_crossbar", (x_post, 0.0, gh + p / 2), (p / 2, gw / 2 + p, p / 2))
    statics.box(
        body, f"goal_{tag}_net_back", (x_line + side * (gd + net), 0.0, gh / 2), (net, gw / 2 + p, gh / 2), damped=True
    )
    statics.box(
        body, f"goal_{tag}_net_top", (x_line + side * gd / 2, 0.0, gh + net), (gd / 2, gw / 2 + p, net), damped=True
    )


def add_ceiling(statics: StaticParts, geo: FieldGeometry) -> None:
    """A slab over the whole world at the ceiling's height (drones fly below it)."""
    half_x, half_y = _half_extent(geo)
    slab = 0.05
    statics.box(statics.body("ceiling"), "ceiling", (0.0, 0.0, geo.ceiling + slab), (half_x, half_y, slab))


def add_ball(spec: mujoco.MjSpec, scene: Scene) -> None:
    """The ball (a hollow sphere on a free joint) at its start, and its contact with the floor."""
    b = scene.ball
    ball = spec.worldbody.add_body(name=BALL_NAME, pos=[b.position[0], b.position[1], b.radius])
    ball.add_freejoint(name="ball")
    ball.add_geom(
        name="ball",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[b.radius, 0, 0],
        mass=b.mass,
        typeinertia=mujoco.mjtGeomInertia.mjINERTIA_SHELL,
        contype=BALL,
        conaffinity=MOUTH | STATIC,
        condim=3,
        friction=[b.friction, 0.005, 0.0001],
    )
    # Rolling resistance: a rolling hollow ball (I = 2/3 m r^2) under rolling friction mu_r decelerates at
    # a = mu_r g / (r (1 + 2/3)); solve for mu_r so that a equals the scene's rolling deceleration.
    g = max(scene.physics.gravity, 1e-9)
    mu_roll = b.rolling_deceleration * b.radius * (1.0 + 2.0 / 3.0) / g
    ball_floor = spec.add_pair(geomname1="floor", geomname2="ball", condim=6)
    ball_floor.friction = [b.friction, b.friction, 0.005, mu_roll, mu_roll]
    # The floor contact itself is critically damped (a soft contact with little damping is unstable at this
    # step size); the simulator applies the ball's restitution at each impact (see Simulator._bounce).
    ball_floor.solref = [2.0 * scene.physics.timestep, 1.0]
    ball_floor.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
    # a softer friction constraint (rolling resistance included) keeps a fast-rolling ball on the floor: its
    # deceleration stays within a few per cent of the setting from 0.1 to 2.5 m/s^2
    ball_floor.solreffriction = [0.1, 1.0]


def robot_entries(scene: Scene) -> tuple[list[RobotEntry], list[RobotEntry]]:
    """The scene's robots with their models, ground robots and aerial ones, each in the scene's order."""
    robots: list[RobotEntry] = []
    for team, tspec in scene.teams.items():
        for m in tspec.members():
            cls = model_class(m.model)
            robots.append(RobotEntry(f"{team}/{m.id}", team, m.id, cls(m.model_params), tuple(m.start)))
    return [r for r in robots if not r.model.aerial], [r for r in robots if r.model.aerial]


def add_robot(spec: mujoco.MjSpec, entry: RobotEntry, scene: Scene) -> None:
    """A ground robot's body (`simatch.robots.body`) and the simulator's two constraints on it, both off at
    the start: the dribbler's hold on the ball and the weld that freezes it where it stands."""
    add_ground_robot(
        spec,
        entry.name,
        entry.model,
        ball_radius=scene.ball.radius,
        timestep=scene.physics.timestep,
        hull=(HULL, HULL | STATIC),
        mouth=(MOUTH, 0),
        mouth_solref=BALL_BODY_SOLREF,
    )
    spec.add_equality(
        name=f"{entry.name}/dribble",
        type=mujoco.mjtEq.mjEQ_CONNECT,
        objtype=mujoco.mjtObj.mjOBJ_BODY,
        name1=entry.name,
        name2=BALL_NAME,
        active=False,
        solref=[0.02, 1.0],
    )
    add_freeze_weld(spec, entry.name, [2.0 * scene.physics.timestep, 1.0])  # as stiff as the step allows


def world_index(model, data, ground: list, flying: list, statics: list, obstacles: list, gravity: float) -> WorldIndex:
    """Where every part of the compiled world lies (robots: ground ones, then aerial ones)."""

    def jq(name: str) -> int:
        return int(model.jnt_qposadr[model.joint(name).id])

    def jv(name: str) -> int:
        return int(model.jnt_dofadr[model.joint(name).id])

    def per_ground(address) -> np.ndarray:  # (Ng, 3): one address per planar joint or servo axis
        return np.array([[address(r.name, k) for k in range(3)] for r in ground], dtype=int).reshape(-1, 3)

    robots = ground + flying
    servo = [model.actuator(f"{r.name}/servo_{a}").id for r in ground for a in "xyw"]
    index = WorldIndex(
        robots=robots,
        robot_body=np.array([model.body(r.name).id for r in robots], dtype=int),
        robot_qpos=per_ground(lambda name, k: jq(f"{name}/{('x', 'y', 'yaw')[k]}")),
        robot_qvel=per_ground(lambda name, k: jv(f"{name}/{('x', 'y', 'yaw')[k]}")),
        robot_ctrl=np.array(servo, dtype=int).reshape(-1, 3),
        robot_act=np.array([model.actuator_actadr[a] for a in servo], dtype=int).reshape(-1, 3),
        robot_hull_geom=np.array([model.geom(f"{r.name}/hull").id for r in robots], dtype=int),
        robot_mouth_geom=np.array([model.geom(f"{r.name}/mouth").id for r in ground], dtype=int),
        dribble_eq=np.array([model.equality(f"{r.name}/dribble").id for r in ground] + [-1] * len(flying), dtype=int),
        freeze_eq=np.array([model.equality(f"{r.name}/freeze").id for r in ground], dtype=int),
        ball_body=model.body(BALL_NAME).id,
        ball_qpos=jq("ball"),
        ball_qvel=jv("ball"),
        ball_geom=model.geom("ball").id,
        static_geoms=np.array([model.geom(s.name).id for s in statics], dtype=int),
        aerial=aerial_index(model, data, flying, len(ground), gravity) if flying else None,
        obstacle_geoms=np.array([model.geom(name).id for name in obstacles], dtype=int),
    )
    for i in range(len(robots)):
        index.robot_of_geom[int(index.robot_hull_geom[i])] = i
        if i < len(ground):
            index.robot_of_geom[int(index.robot_mouth_geom[i])] = i
    return index
