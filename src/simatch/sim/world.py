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

from dataclasses import dataclass, field

import mujoco
import numpy as np

from ..config.schema import Scene
from ..field import FieldGeometry, Obstacle
from ..robots import HULL_HEIGHT, RobotModel, model_class
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
        g.quat = [np.cos(ob.yaw / 2), 0.0, 0.0, np.sin(ob.yaw / 2)]
    return ob.name


def build_world(scene: Scene) -> tuple[mujoco.MjModel, mujoco.MjData, WorldIndex, FieldGeometry]:
    spec = mujoco.MjSpec()
    spec.modelname = scene.name
    opt = spec.option
    opt.timestep = scene.physics.timestep
    opt.gravity = [0.0, 0.0, -scene.physics.gravity]
    opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    # elliptic friction cones: with pyramidal ones the rolling-friction rows of the ball's floor contact
    # make a rolling ball hop and slip (measured); elliptic cones roll it cleanly
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.iterations = scene.physics.solver_iterations
    opt.tolerance = scene.physics.solver_tolerance
    # measured on the msl_5v5 benchmark, same trajectories either way: the mid-phase tree only costs time
    # with a handful of primitives per body, and no joint has damping for Euler to treat implicitly
    opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MIDPHASE | mujoco.mjtDisableBit.mjDSBL_EULERDAMP
    geo = scene.world.geometry()
    wb = spec.worldbody

    half_x = geo.half_length + geo.margin
    half_y = geo.half_width + geo.margin
    floor = wb.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[half_x + 2.0, half_y + 2.0, 0.1],
        contype=FLOOR,
        conaffinity=0,
        condim=3,
    )

    statics: list = []

    # Every board and goal is a static body of its own: the broad phase then pairs a robot or the ball
    # only with the static parts near it (geoms of the world body share one huge bounding box).
    def static_body(name: str):
        return wb.add_body(name=name)

    def static_box(body, name: str, center, half_sizes, damped: bool = False, kind=mujoco.mjtGeom.mjGEOM_BOX):
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
        statics.append(g)
        return g

    if geo.walls:
        t, h = 0.05, geo.wall_height
        for name, center, size in (
            ("board_+x", (half_x + t, 0, h / 2), (t, half_y + 2 * t, h / 2)),
            ("board_-x", (-half_x - t, 0, h / 2), (t, half_y + 2 * t, h / 2)),
            ("board_+y", (0, half_y + t, h / 2), (half_x, t, h / 2)),
            ("board_-y", (0, -half_y - t, h / 2), (half_x, t, h / 2)),
        ):
            static_box(static_body(name), name, center, size)

    if geo.goals:
        p, gw, gh, gd = geo.goal_post_size, geo.goal_width, geo.goal_height, geo.goal_depth
        net = 0.01
        for side, tag in ((-1, "cyan"), (1, "magenta")):
            body = static_body(f"goal_{tag}")
            x_line = side * geo.half_length
            x_post = x_line + side * p / 2
            for sy, ytag in ((1, "left"), (-1, "right")):
                static_box(
                    body,
                    f"goal_{tag}_post_{ytag}",
                    (x_post, sy * (gw / 2 + p / 2), (gh + p) / 2),
                    (p / 2, p / 2, (gh + p) / 2),
                )
                static_box(
                    body,
                    f"goal_{tag}_net_{ytag}",
                    (x_line + side * gd / 2, sy * (gw / 2 + p + net), gh / 2),
                    (gd / 2, net, gh / 2),
                    damped=True,
                )
            static_box(body, f"goal_{tag}_crossbar", (x_post, 0.0, gh + p / 2), (p / 2, gw / 2 + p, p / 2))
            static_box(
                body,
                f"goal_{tag}_net_back",
                (x_line + side * (gd + net), 0.0, gh / 2),
                (net, gw / 2 + p, gh / 2),
                damped=True,
            )
            static_box(
                body,
                f"goal_{tag}_net_top",
                (x_line + side * gd / 2, 0.0, gh + net),
                (gd / 2, gw / 2 + p, net),
                damped=True,
            )

    obstacle_names = [add_obstacle(static_body, static_box, ob) for ob in geo.obstacles]
    if geo.ceiling is not None:
        slab = 0.05
        static_box(static_body("ceiling"), "ceiling", (0.0, 0.0, geo.ceiling + slab), (half_x, half_y, slab))

    # --- ball -----------------------------------------------------------------------------------------------
    b = scene.ball
    ball = wb.add_body(name=BALL_NAME, pos=[b.position[0], b.position[1], b.radius])
    ball.add_freejoint(name="ball")
    ball_geom = ball.add_geom(
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
    # a softer friction constraint (rolling resistance included) keeps a fast-rolling ball on the floor:
    # measured deceleration within 4 % of the setting from 0.1 to 2.5 m/s^2
    ball_floor.solreffriction = [0.1, 1.0]

    # --- robots -----------------------------------------------------------------------------------------
    robots: list[RobotEntry] = []
    for team, tspec in scene.teams.items():
        for m in tspec.members():
            cls = model_class(m.model)
            robots.append(RobotEntry(f"{team}/{m.id}", team, m.id, cls(m.model_params), tuple(m.start)))
    flying = [r for r in robots if r.model.aerial]
    robots = [r for r in robots if not r.model.aerial]  # ground robots first: their joints are consecutive

    for entry in robots:
        model = entry.model
        p = model.params
        body = wb.add_body(name=entry.name, pos=[0.0, 0.0, 0.0])
        body.add_joint(name=f"{entry.name}/x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        body.add_joint(name=f"{entry.name}/y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        body.add_joint(name=f"{entry.name}/yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
        body.mass = model.mass
        body.inertia = list(model.inertia())
        body.ipos = [0.0, 0.0, p.height / 2]
        body.explicitinertial = True
        body.add_geom(
            name=f"{entry.name}/hull",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            pos=[0, 0, HULL_HEIGHT],
            size=[p.radius, 0, 0],
            contype=HULL,
            conaffinity=HULL | STATIC,
            condim=1,
            mass=0,
        )
        cx, cr = model.ball_collider(b.radius)
        body.add_geom(
            name=f"{entry.name}/mouth",
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            fromto=[cx, 0, b.radius, cx, 0, max(p.height - cr, b.radius + 1e-3)],
            size=[cr, 0, 0],
            contype=MOUTH,
            conaffinity=0,
            condim=3,
            friction=[0.3, 0.005, 0.0001],
            mass=0,
            solref=BALL_BODY_SOLREF,
        )
        body.add_site(name=f"{entry.name}/base", pos=[0, 0, 0])
        # The base's velocity servo, one per body axis (x, y, turn), acting in the robot frame through a
        # site: force = kv (act - v) + bias, bounded by the traction limit. With the default response time
        # of one physics step it is deadbeat: the base moves at its set point unless traction limits it.
        # The set point is the actuator's activation, integrated by the engine from ctrl (its rate of
        # change) and clamped at the target (actrange), so a planned wheel ramp runs without Python; the
        # bias carries a small correction for exact arcs (see Simulator._plan_drive).
        tau = p.response_time or scene.physics.timestep
        for k, gear in enumerate(([1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1])):
            act = spec.add_actuator(
                name=f"{entry.name}/servo_{'xyw'[k]}",
                trntype=mujoco.mjtTrn.mjTRN_SITE,
                target=f"{entry.name}/base",
                gear=gear,
            )
            inertia = model.mass if k < 2 else model.inertia()[2]
            kv = inertia / tau
            act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
            act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            act.gainprm[0] = kv
            act.biasprm[0:3] = [0.0, 0.0, -kv]
            act.actearly = True
            act.actlimited = True
            act.actrange = [-1.0, 1.0]  # set at run time by every plan
            act.forcelimited = True
            limit = p.max_force if k < 2 else p.max_torque
            act.forcerange = [-limit, limit]
        spec.add_equality(
            name=f"{entry.name}/dribble",
            type=mujoco.mjtEq.mjEQ_CONNECT,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=entry.name,
            name2=BALL_NAME,
            active=False,
            solref=[0.02, 1.0],
        )
        spec.add_equality(
            name=f"{entry.name}/freeze",
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=entry.name,
            name2="world",
            active=False,
            solref=[2.0 * scene.physics.timestep, 1.0],
        )  # as stiff as the step allows
    for entry in flying:
        add_airframe(spec, entry, AIR, FLOOR | HULL | BALL | STATIC | AIR)
    ground = robots
    robots = ground + flying

    model = spec.compile()
    data = mujoco.MjData(model)

    def jq(name: str) -> int:
        return int(model.jnt_qposadr[model.joint(name).id])

    def jv(name: str) -> int:
        return int(model.jnt_dofadr[model.joint(name).id])

    index = WorldIndex(
        robots=robots,
        robot_body=np.array([model.body(r.name).id for r in robots], dtype=int),
        robot_qpos=np.array([[jq(f"{r.name}/{j}") for j in ("x", "y", "yaw")] for r in ground], dtype=int).reshape(
            -1, 3
        ),
        robot_qvel=np.array([[jv(f"{r.name}/{j}") for j in ("x", "y", "yaw")] for r in ground], dtype=int).reshape(
            -1, 3
        ),
        robot_ctrl=np.array(
            [[model.actuator(f"{r.name}/servo_{a}").id for a in "xyw"] for r in ground], dtype=int
        ).reshape(-1, 3),
        robot_act=np.array(
            [[model.actuator_actadr[model.actuator(f"{r.name}/servo_{a}").id] for a in "xyw"] for r in ground],
            dtype=int,
        ).reshape(-1, 3),
        robot_hull_geom=np.array([model.geom(f"{r.name}/hull").id for r in robots], dtype=int),
        robot_mouth_geom=np.array([model.geom(f"{r.name}/mouth").id for r in ground], dtype=int),
        dribble_eq=np.array([model.equality(f"{r.name}/dribble").id for r in ground] + [-1] * len(flying), dtype=int),
        freeze_eq=np.array([model.equality(f"{r.name}/freeze").id for r in ground], dtype=int),
        ball_body=model.body(BALL_NAME).id,
        ball_qpos=jq("ball"),
        ball_qvel=jv("ball"),
        ball_geom=model.geom("ball").id,
        static_geoms=np.array([model.geom(s.name).id for s in statics], dtype=int),
        aerial=aerial_index(model, data, flying, len(ground), scene.physics.gravity) if flying else None,
        obstacle_geoms=np.array([model.geom(name).id for name in obstacle_names], dtype=int),
    )
    for i, r in enumerate(robots):
        index.robot_of_geom[int(index.robot_hull_geom[i])] = i
        if i < len(ground):
            index.robot_of_geom[int(index.robot_mouth_geom[i])] = i
            x, y, yaw = r.start
            data.qpos[index.robot_qpos[i]] = (x, y, yaw)
    mujoco.mj_forward(model, data)
    del floor, ball_geom
    return model, data, index, geo
