"""The fuzzing targets: every place where simatch takes input it does not control, each as a Hypothesis test
(a property over generated inputs) that fails only on a **crash**: an exception other than the documented
error of that input, a verdict that differs between two implementations, a hang, or a corrupted physics state
(a NaN in the state, a robot outside the world).

`scripts/fuzz.py` runs a timed campaign over them (``fuzz_one_input`` with fresh random or atheris-mutated
buffers, counting inputs, crashes and coverage); `tests/fuzz/test_fuzz.py` runs a short deterministic slice in
the test suite. Each target is named in `TARGETS`; `MODULES` are the source files whose coverage the campaign
reports.

Where one input is cheap (a payload to decode, a text to parse), a Hypothesis example is a *seed* (a valid
message of any type, a bundle, a page's message, a ``--set`` text) and the target tries it and a few hundred
variants of it made by a mutation loop (`variants`: cut at every length, bits flipped, lengths overwritten,
bytes inserted and removed), each one an input: Hypothesis's generation costs milliseconds, a decoder
microseconds. `COUNTS` counts the inputs each target tried.

Targets:

* ``cdr``: every simatch message type's CDR decoder, the C codec against rosbags' own deserializer (the
  reference), on valid messages, on valid messages cut, bit-flipped, with lengths overwritten, and on plain
  bytes: both give the same verdict (the same message, or both refuse it: the C codec with `MessageError`
  alone), and a decoded message encodes again;
* ``bundle``: the distributed protocol's bundles (`simatch.bus.bundle`) and JSON payloads
  (`simatch.distributed.protocol`), the signatures of samples (`credentials`) and the server's fair-play
  verdict on any sample (`fairplay`), and a scene offer as a server would send it;
* ``websocket``: the web UI's WebSocket messages (`simatch.web.protocol.parse`), and those that parse carried
  out by a live run's control (a referee's and a coach's) in a real match;
* ``scene``: scene files (a shipped scene's text with lines dropped, values replaced, keys added) and
  ``--set`` values; a scene that loads is built and stepped;
* ``recording``: recordings truncated, bit-flipped, with records reordered, duplicated or replaced: read,
  replayed, verified and recovered (the recovered file must read whole with the plain ``mcap`` reader);
* ``commands``: robot commands and world calls with any values (NaN, infinities, huge, wrong types) on a real
  simulator, stepped: no NaN in the state, no robot outside the boards.
"""

from __future__ import annotations

import collections
import functools
import json
import math
import random
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rosbags.typesys.base import Nodetype

from simatch import msgs

MODULES = [
    "simatch/msgs/cdr.py",
    "simatch/msgs/__init__.py",
    "simatch/bus/bundle.py",
    "simatch/distributed/protocol.py",
    "simatch/distributed/credentials.py",
    "simatch/distributed/fairplay.py",
    "simatch/web/protocol.py",
    "simatch/web/control.py",
    "simatch/config/loader.py",
    "simatch/config/schema.py",
    "simatch/record/reader.py",
    "simatch/record/recover.py",
    "simatch/record/reproduce.py",
    "simatch/sim/simulator.py",
    "simatch/sim/inputs.py",
    "simatch/sim/ballhandling.py",
]


# --- generic values --------------------------------------------------------------------------------------------
FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-320, 1e308, -1e308, 3.4e38, 1e4, -1e4, 50.0, 50.000001, 100.0, 1e5]),
)
ODD = st.one_of(
    FLOATS,
    st.integers(min_value=-(2**70), max_value=2**70),
    st.booleans(),
    st.none(),
    st.text(max_size=8),
    st.lists(st.floats(), max_size=3),
)


def _base(name: str):
    if name == "bool":
        return st.booleans()
    if name == "string":
        return st.text(max_size=12)
    if name in ("float32", "float64"):
        return st.floats(width=32 if name == "float32" else 64)
    if name == "char" or name == "octet" or name == "byte":
        return st.integers(0, 255)
    bits = int("".join(c for c in name if c.isdigit()) or 8)
    if name.startswith("u"):
        return st.integers(0, 2**bits - 1)
    return st.integers(-(2 ** (bits - 1)), 2 ** (bits - 1) - 1)


_DTYPES = {
    "float64": np.float64,
    "float32": np.float32,
    "int8": np.int8,
    "int16": np.int16,
    "int32": np.int32,
    "int64": np.int64,
    "uint8": np.uint8,
    "uint16": np.uint16,
    "uint32": np.uint32,
    "uint64": np.uint64,
}


@functools.cache
def message_strategy(typename: str, depth: int = 0):
    """Any message of ``typename`` (every field drawn; sequences short)."""
    _, fields = msgs.typestore.fielddefs[typename]
    parts = {}
    for fname, (kind, info) in fields:
        parts[fname] = _field(kind, info, depth)
    return st.fixed_dictionaries(parts).map(lambda d: msgs.new(typename, **d))


def _field(kind, info, depth):
    if kind == Nodetype.BASE:
        return _base(info[0])
    if kind == Nodetype.NAME:
        return message_strategy(info, depth + 1) if depth < 3 else st.builds(msgs.new, st.just(info))
    inner, length = info
    n = length if kind == Nodetype.ARRAY else None
    if inner[0] == Nodetype.BASE and inner[1][0] in _DTYPES:
        dtype = _DTYPES[inner[1][0]]
        size = st.just(n) if n is not None else st.integers(0, 6)
        return size.flatmap(lambda k: st.lists(_base(inner[1][0]), min_size=k, max_size=k)).map(
            lambda v: np.array(v, dtype=dtype)
        )
    element = _field(inner[0], inner[1], depth + 1)
    return st.lists(element, min_size=n or 0, max_size=n if n is not None else 3)


@st.composite
def mutated(draw, data: bytes) -> bytes:
    """``data`` cut, with bits flipped, a 4-byte length overwritten, bytes inserted or removed (or as it is)."""
    out = bytearray(data)
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(["cut", "flip", "length", "insert", "delete", "splice"]))
        at = draw(st.integers(0, max(0, len(out) - 1)))
        if op == "cut":
            out = out[:at]
        elif op == "flip" and out:
            out[at] ^= 1 << draw(st.integers(0, 7))
        elif op == "length" and len(out) >= at + 4:
            out[at : at + 4] = draw(st.sampled_from([0, 1, 7, 255, 2**16, 2**31 - 1, 2**32 - 1])).to_bytes(4, "little")
        elif op == "insert":
            out[at:at] = draw(st.binary(max_size=16))
        elif op == "delete":
            del out[at : at + draw(st.integers(1, 16))]
        elif op == "splice":
            out[at:] = draw(st.binary(max_size=64))
    return bytes(out)


#: inputs tried, per target
COUNTS: collections.Counter = collections.Counter()


def variants(data: bytes, seed: int, k: int):
    """``data`` and ``k`` variants of it: cut short, bits flipped, a 4-byte length overwritten, bytes inserted,
    removed or duplicated (a fast mutation loop, deterministic for a seed)."""
    rng = random.Random(seed)
    yield data
    n = len(data)
    for _ in range(k):
        out = bytearray(data)
        for _ in range(rng.choice((1, 1, 2, 3))):
            at = rng.randrange(len(out) + 1)
            op = rng.randrange(7)
            if op == 0:
                del out[at:]
            elif op == 1 and out:
                out[min(at, len(out) - 1)] ^= 1 << rng.randrange(8)
            elif op == 2 and len(out) >= at + 4:
                out[at : at + 4] = rng.choice((0, 1, 3, 255, 65536, 2**31 - 1, 2**32 - 1)).to_bytes(4, "little")
            elif op == 3:
                out[at:at] = rng.randbytes(rng.randrange(1, 9))
            elif op == 4:
                del out[at : at + rng.randrange(1, 9)]
            elif op == 5 and n:
                j = rng.randrange(n)
                out[at:at] = data[j : j + rng.randrange(1, 17)]
            elif out:
                out[min(at, len(out) - 1)] = rng.choice((0, 0x7F, 0x80, 0xFF))
        yield bytes(out)


# --- cdr ---------------------------------------------------------------------------------------------------------
TYPES = sorted(msgs.names())


@functools.cache
def _codecs():
    from simatch.msgs.cdr import Codec

    c = Codec(msgs.typestore)
    rosbags = Codec(msgs.typestore, accelerate=False)  # (decodes with rosbags' deserializer)
    return c, rosbags


def _verdict(codec, typename, data):
    try:
        msg = codec.decode(typename, data)
    except msgs.MessageError:
        return None
    return msg


@st.composite
def cdr_inputs(draw):
    typename = draw(st.sampled_from(TYPES))
    if draw(st.integers(0, 4)) == 0:
        data = draw(st.binary(max_size=256))
        if draw(st.booleans()):
            data = b"\x00\x01\x00\x00" + data
    else:
        data = msgs.encode(draw(message_strategy(typename)))
    return typename, data, draw(st.integers(0, 2**32))


def target_cdr(case):
    typename, seed_data, seed = case
    c, rosbags = _codecs()
    types = [typename] + random.Random(seed).sample(TYPES, 2)  # the same bytes read as other types too
    for data in variants(seed_data, seed, 300):
        for name in types:
            COUNTS["cdr"] += 1
            a, b = _verdict(c, name, data), _verdict(rosbags, name, data)
            assert (a is None) == (b is None), (
                f"C {'refused' if a is None else 'accepted'} and rosbags did not: {name} {data!r}"
            )
            if a is not None:
                assert rosbags.encode(a, name) == rosbags.encode(b, name), (
                    f"C and rosbags decode {name} differently: {data!r}"
                )
                assert msgs.encode(a) == rosbags.encode(a, name)


# --- distributed protocol --------------------------------------------------------------------------------------
@functools.cache
def _fairplay():
    from simatch.config.loader import load_scene
    from simatch.distributed import credentials
    from simatch.distributed.fairplay import FairPlay

    spec = load_scene("msl_5v5").spec
    teams = {t: spec.teams[t].robot_ids() for t in spec.teams}
    creds = {
        name: credentials.Credential(name, (name.encode() * 32).hex()[:64]) for name in [*teams, credentials.ADMIN]
    }
    return FairPlay("fuzz", creds, teams), creds


TOPICS = st.one_of(
    st.sampled_from(
        [
            "cyan/2/VelCmd",
            "magenta/3/ActionCmd",
            "cyan/TeamStrategy",
            "cyan/lockstep/ack",
            "cyan/lockstep/bundle",
            "events",
            "set_model_state",
            "referee_command",
            "world_inputs",
            "cyan/9/VelCmd",
            "",
            "/",
            "cyan//VelCmd",
        ]
    ),
    st.text(max_size=24),
)


@st.composite
def bundles(draw):
    from simatch.bus import bundle

    entries = draw(
        st.lists(
            st.tuples(TOPICS, st.sampled_from(["", "simatch_msgs/msg/VelCmd"]), st.binary(max_size=40)), max_size=4
        )
    )
    try:
        data = bundle.pack(entries)
    except ValueError:
        data = b"SMB1"
    return draw(st.one_of(st.just(data), mutated(data), st.binary(max_size=80)))


JSONISH = st.recursive(
    st.one_of(st.none(), st.booleans(), FLOATS, st.integers(), st.text(max_size=10)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12,
)


def target_bundle(data, payload, topic, attachment, signer):
    import json

    from simatch.bus import bundle
    from simatch.distributed import credentials, protocol
    from simatch.distributed.fairplay import Refusal

    fair, creds = _fairplay()
    for variant in variants(data, len(data) + len(payload), 100):
        COUNTS["bundle"] += 1
        try:
            for entry in bundle.unpack(variant):
                assert isinstance(entry.topic, str) and isinstance(entry.msgtype, str)
                assert isinstance(entry.payload, bytes)
                verdict = fair.check_entry(attachment, entry.topic, entry.payload)
                assert verdict is None or isinstance(verdict, Refusal)
        except bundle.BundleError:
            pass
    for variant in variants(payload, len(payload), 50):
        COUNTS["bundle"] += 1
        try:
            msg = protocol.loads(variant, "proc", "tick")
            assert isinstance(msg, dict) and "proc" in msg and "tick" in msg
        except protocol.ProtocolError:
            pass
    if signer in creds and attachment is not None and len(attachment) % 2:  # half of them signed for real
        attachment = creds[signer].signer("fuzz")(topic, payload)
    for variant in variants(attachment or b"", len(topic), 50):
        COUNTS["bundle"] += 1
        verdict = fair.check(topic, payload, variant or None)
        assert verdict is None or isinstance(verdict, Refusal)
        credentials.claimed_name(variant)
        for entry_attachment in (variant, None):
            verdict = fair.check_entry(entry_attachment, topic, payload)
            assert verdict is None or isinstance(verdict, Refusal)
    try:  # what a client makes of a scene offer (a server it does not control)
        offer = json.loads(payload) if payload[:1] in (b"{", b"[") else {"scene": payload.decode("latin-1")}
        protocol.scene_from_offer(offer if isinstance(offer, dict) else {"scene": offer})
    except (protocol.ProtocolError, ValueError, TypeError, KeyError):
        pass


# --- web ---------------------------------------------------------------------------------------------------------
WEB_KINDS = [
    "command",
    "limits",
    "test",
    "place_ball",
    "send_off",
    "pause",
    "resume",
    "card",
    "award_goal",
    "auto_referee",
    "timeline",
]
WEB_KEYS = ["type", "cmd", "team", "robot", "x", "y", "max_vel", "max_w", "mode", "off", "card", "on", "id", "t"]


@st.composite
def web_texts(draw):
    import json

    if draw(st.integers(0, 4)) == 0:
        return draw(st.one_of(st.text(max_size=60), st.binary(max_size=60)))
    obj = {"type": draw(st.one_of(st.sampled_from(WEB_KINDS), st.text(max_size=6)))}
    for key in draw(st.lists(st.sampled_from(WEB_KEYS[1:]), max_size=5, unique=True)):
        obj[key] = draw(
            st.one_of(
                JSONISH,
                st.sampled_from(["cyan", "magenta", "cyan/2", "magenta/9", "STARTROBOT", "yellow", "red", "move"]),
                st.floats(-30, 30),
            )
        )
    text = json.dumps(obj)
    return draw(st.one_of(st.just(text), mutated(text.encode()).map(lambda b: b.decode("utf-8", "replace"))))


class _Live:
    """A real refereed match with a web control (made once per process, stepped by the target)."""

    def __init__(self):
        import simatch
        from simatch.web.control import RunControl

        self.sim = simatch.Simulation("msl_5v5", seed=1)
        self.control = RunControl(self.sim)
        self.sim.step()
        self.coached = simatch.Simulation("msl_5v5", seed=1, overrides={"judge.kind": "none"})
        self.coached_control = RunControl(self.coached)


@functools.cache
def _live() -> _Live:
    return _Live()


def target_websocket(text, role, team):
    from simatch.web import protocol as P
    from simatch.web.access import Grant

    raw = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    parsed = []
    for n, variant in enumerate(variants(raw, len(raw), 100)):
        COUNTS["websocket"] += 1
        candidate = variant if n % 2 else variant.decode("utf-8", "replace")
        P.message_id(candidate)
        try:
            message = P.parse(candidate, role)
            P.authorize(message, role, team)
        except P.ProtocolError:
            continue
        if role != "replay" and len(parsed) < 2:
            parsed.append(message)
    live = _live()
    for message in parsed:  # carried out in real runs
        for sim, control in ((live.sim, live.control), (live.coached, live.coached_control)):
            answers = []
            control.submit(Grant(role, team if role == "coach" else ""), message, answers.append)
            for _ in range(3):
                sim.step()
                if answers:
                    break
            assert all(a is None or isinstance(a, str) for a in answers)
            check_world(sim.simulator)


# --- scene files and --set ----------------------------------------------------------------------------------------
@functools.cache
def _scene_text(name: str) -> str:
    from simatch.config.loader import resolve

    return resolve(name)[1]


TOML_VALUES = st.one_of(
    st.sampled_from(["0", "-1", "1e309", "nan", "inf", "-inf", '"x"', "[]", "[[0,0,0]]", "true", "{}", "1e-12"]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**6), 10**6).map(str),
)
SET_KEYS = st.sampled_from(
    [
        "physics.timestep",
        "control.period",
        "control.command_timeout",
        "ball.radius",
        "ball.restitution",
        "teams.cyan.ids",
        "teams.cyan.start",
        "teams.magenta.model",
        "teams.cyan.strategy",
        "field.length",
        "field.width",
        "field.margin",
        "perception.position_noise",
        "perception.delay",
        "judge.kind",
        "match.half_duration",
        "duration",
        "kicker.max_speed",
        "dribbler.grip_force",
        "nonsense.key",
    ]
)


@st.composite
def scene_texts(draw):
    lines = _scene_text(draw(st.sampled_from(["msl_5v5", "omni_circle", "encirclement_9v7"]))).splitlines()
    for _ in range(draw(st.integers(0, 4))):
        if not lines:
            break
        at = draw(st.integers(0, len(lines) - 1))
        op = draw(st.integers(0, 3))
        if op == 0:
            del lines[at]
        elif op == 1 and "=" in lines[at]:
            key = lines[at].split("=", 1)[0]
            lines[at] = f"{key}= {draw(TOML_VALUES)}"
        elif op == 2:
            lines.insert(at, draw(st.text(max_size=30)))
        else:
            lines.insert(at, f"{draw(st.text(alphabet='abcxyz_', min_size=1, max_size=8))} = {draw(TOML_VALUES)}")
    return "\n".join(lines)


def target_scene(text, sets, raw_set):
    from simatch.config.loader import SceneError, check_models, parse_override, scene_from_text
    from simatch.sim.simulator import Simulator

    for variant in variants(raw_set.encode(), len(raw_set), 100):
        COUNTS["scene"] += 1
        try:
            parse_override(variant.decode("utf-8", "replace"))
        except SceneError:
            pass
    COUNTS["scene"] += 1
    overrides = {}
    for key, value in sets:
        try:
            k, v = parse_override(f"{key}={value}")
        except SceneError:
            continue
        overrides[k] = v
    try:
        scene = scene_from_text(text, "fuzz.toml", overrides)
        check_models(scene)
    except SceneError:
        return
    if len(scene.spec.robot_names()) > 40 or scene.spec.physics.timestep < 1e-4:
        return  # valid, and too large to step here
    sim = Simulator(scene.spec, 0)
    for _ in range(5):
        sim.advance()
    check_world(sim)


# --- recordings ---------------------------------------------------------------------------------------------------
@functools.cache
def _recording() -> bytes:
    """A small real recording (omni_circle, 1.2 s, several chunks), made once per process."""
    import simatch
    from simatch.record import Recorder

    with tempfile.TemporaryDirectory(prefix="simatch-fuzz-") as tmp:
        path = Path(tmp) / "base.mcap"
        with simatch.Simulation("omni_circle", seed=1) as sim, Recorder.for_run(sim, path):
            sim.set_model_state("ball", x=0.5, y=0.2, vx=1.0)
            sim.run(seconds=1.2)
        return path.read_bytes()


def _records(data: bytes) -> list[tuple[int, int]]:
    """(offset, length) of every top-level record of an MCAP file (after the magic)."""
    out, at = [], 8
    while at + 9 <= len(data) - 8:
        n = int.from_bytes(data[at + 1 : at + 9], "little")
        if at + 9 + n > len(data):
            break
        out.append((at, 9 + n))
        at += 9 + n
    return out


def _cli(argv: list[str]) -> int:
    """A simatch command as a user runs it; its documented failure is exit status 2 with one line."""
    import contextlib
    import io

    from simatch.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    assert code in (0, 1, 2), code
    assert "Traceback" not in err.getvalue()
    return code


@st.composite
def recordings(draw):
    data = bytearray(_recording())
    records = _records(bytes(data))
    op = draw(st.sampled_from(["truncate", "flip", "reorder", "duplicate", "replace", "mutate"]))
    if op == "truncate":
        return bytes(data[: draw(st.integers(0, len(data)))])
    if op == "flip":
        for _ in range(draw(st.integers(1, 4))):
            at = draw(st.integers(0, len(data) - 1))
            data[at] ^= 1 << draw(st.integers(0, 7))
        return bytes(data)
    i, j = sorted(draw(st.lists(st.integers(0, len(records) - 1), min_size=2, max_size=2)))
    (a, la), (b, lb) = records[i], records[j]
    if op == "reorder" and i != j:
        return bytes(data[:a] + data[b : b + lb] + data[a + la : b] + data[a : a + la] + data[b + lb :])
    if op == "duplicate":
        return bytes(data[: b + lb] + data[a : a + la] + data[b + lb :])
    if op == "replace":
        return bytes(data[:a] + draw(st.binary(max_size=la + 8)) + data[a + la :])
    return draw(mutated(bytes(data)))


def target_recording(data):
    from mcap.reader import make_reader

    from simatch.record import Recording, RecordingError, VerifyError, verify
    from simatch.record.recover import RecoverError, recover

    COUNTS["recording"] += 1
    with tempfile.TemporaryDirectory(prefix="simatch-fuzz-") as tmp:
        path = Path(tmp) / "fuzzed.mcap"
        path.write_bytes(data)
        try:
            rec = Recording(path)
        except RecordingError:
            rec = None
        if rec is not None:
            _cli(["replay", str(path), "--info", "--json"])
            _cli(["replay", str(path), "--info"])
            kept = sum(1 for _ in rec.raw())
            for _ in rec.messages():
                pass
            try:
                verify(path)
            except (VerifyError, RecordingError):
                pass
        out = Path(tmp) / "recovered.mcap"
        try:
            report = recover(path, out)
        except RecoverError:
            return
        with open(out, "rb") as f:  # the plain mcap reader reads every recovered file whole
            assert sum(1 for _ in make_reader(f).iter_messages()) == report.messages
        if rec is not None:
            assert report.messages <= max(kept, report.messages)  # (records reordered may move messages)
        Recording(out)


# --- robot commands and world calls -------------------------------------------------------------------------------
CALLS = st.sampled_from(
    ["vel", "action", "all", "set_model_state", "apply_wrench", "set_enabled", "set_frozen", "step", "stop_robot"]
)
STATE_KEYS = ["x", "y", "z", "yaw", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz", "bad"]


@st.composite
def operations(draw):
    ops = []
    for _ in range(draw(st.integers(1, 12))):
        call = draw(CALLS)
        robot = draw(st.one_of(st.integers(0, 10), st.sampled_from([-1, 11, 2**40])))
        if call == "vel":
            ops.append((call, robot, [draw(ODD) for _ in range(3)]))
        elif call == "action":
            ops.append((call, robot, [draw(ODD), draw(ODD), draw(ODD), draw(st.one_of(st.none(), FLOATS))]))
        elif call == "all":
            ops.append((call, robot, [draw(st.lists(FLOATS, min_size=30, max_size=30)), draw(st.booleans())]))
        elif call == "set_model_state":
            state = {k: draw(ODD) for k in draw(st.lists(st.sampled_from(STATE_KEYS), max_size=5, unique=True))}
            name = draw(st.sampled_from(["ball", "cyan/2", "magenta/1", "cyan/9", "nobody", ""]))
            ops.append((call, name, state))
        elif call == "apply_wrench":
            ops.append(
                (call, draw(st.sampled_from(["ball", "cyan/3", "x"])), [[draw(ODD) for _ in range(3)], draw(ODD)])
            )
        elif call in ("set_enabled", "set_frozen"):
            ops.append((call, draw(st.sampled_from(["cyan/4", "magenta/5", "nope"])), draw(ODD)))
        elif call == "stop_robot":
            ops.append((call, robot, None))
        else:
            ops.append((call, draw(st.integers(1, 40)), None))
    return ops


@functools.cache
def _world_template():
    from simatch.config.loader import load_scene

    return load_scene("msl_5v5", {"judge.kind": "none"}).spec


def check_world(sim) -> None:
    """No NaN in the physics state, no robot outside the boards."""
    d = sim.d
    assert np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all(), "NaN or infinity in the physics state"
    f = sim.field
    R = sim.robot_positions()
    assert (np.abs(R[:, 0]) <= f.half_length + f.margin + 0.01).all() and (
        np.abs(R[:, 1]) <= f.half_width + f.margin + 0.01
    ).all(), f"a robot outside the world: {R[:, :2].tolist()}"


def _inside(sim, state: dict) -> dict:
    """Placements inside the boards (a request to place a robot beyond them is the caller's business)."""
    f = sim.field
    out = dict(state)
    for k, half in (("x", f.half_length + f.margin - 0.3), ("y", f.half_width + f.margin - 0.3)):
        v = out.get(k)
        if isinstance(v, float | int) and not isinstance(v, bool) and math.isfinite(v) and abs(v) > half:
            out[k] = math.copysign(half, v)
    return out


def target_commands(ops):
    from simatch.sim.simulator import CommandError, Simulator

    COUNTS["commands"] += 1
    sim = Simulator(_world_template(), 0)
    for call, who, args in ops:
        try:
            if call == "vel":
                sim.command_velocity(who, *args)
            elif call == "action":
                sim.command_action(who, *args)
            elif call == "all":
                V = np.array(args[0][: sim.n * 3], dtype=float).reshape(sim.n, 3)
                sim.command_all(V, np.full(sim.n, args[1]) if args[1] else None)
            elif call == "set_model_state":
                sim.set_model_state(who, **_inside(sim, args))
            elif call == "apply_wrench":
                sim.apply_wrench(who, force=args[0], torque=(0.0, 0.0, 0.0), duration=args[1])
            elif call == "set_enabled":
                sim.set_enabled(who, bool(args) if not isinstance(args, float) or not math.isnan(args) else False)
            elif call == "set_frozen":
                sim.set_frozen(who, bool(args) if not isinstance(args, float) or not math.isnan(args) else False)
            elif call == "stop_robot":
                sim.stop_robot(who)
            else:
                for _ in range(who):
                    sim.advance()
        except CommandError:
            pass  # the documented refusal
        except IndexError:
            if not isinstance(who, int) or 0 <= who < sim.n:
                raise  # a robot index out of range is the caller's error (the bus adapter never makes one)
        check_world(sim)
    for _ in range(20):
        sim.advance()
    check_world(sim)


class Target:
    """A property and the strategies of its arguments; `test` makes the Hypothesis test of it."""

    def __init__(self, prop, *strategies, slow: bool = False):
        self.prop, self.strategies, self.slow = prop, strategies, slow

    def test(self, **options):
        """The Hypothesis test (no deadline: a real simulator steps; no example database)."""
        options = {"deadline": None, "database": None, "suppress_health_check": list(HealthCheck), **options}
        return settings(**options)(given(*self.strategies)(self.prop))


TARGETS = {
    "cdr": Target(target_cdr, cdr_inputs()),
    "bundle": Target(
        target_bundle,
        bundles(),
        st.one_of(st.binary(max_size=64), JSONISH.map(lambda v: json.dumps(v).encode())),
        TOPICS,
        st.one_of(st.none(), st.binary(max_size=60)),
        st.sampled_from(["cyan", "magenta", "admin", "nobody"]),
    ),
    "websocket": Target(
        target_websocket,
        web_texts(),
        st.sampled_from(["coach", "referee", "replay"]),
        st.sampled_from(["cyan", "magenta"]),
    ),
    "scene": Target(
        target_scene,
        scene_texts(),
        st.lists(st.tuples(SET_KEYS, TOML_VALUES), max_size=3),
        st.text(max_size=30),
        slow=True,
    ),
    "recording": Target(target_recording, recordings(), slow=True),
    "commands": Target(target_commands, operations(), slow=True),
}
