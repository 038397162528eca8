"""The recorder's message log (``Log``, record/_messagelog.c): the records it writes, its clock, chunks, memo,
pose template and lent memory."""

from __future__ import annotations

import mmap

import numpy as np
import pytest

import simatch
from simatch import msgs
from simatch.bus.inproc import InProcessBus
from simatch.record import Recorder, Recording
from simatch.record.messagelog import CLOCK_STEP, CLOCK_TICK, MESSAGE_HEADER, new_log


def _records(data: bytes) -> list[tuple[int, int, bytes]]:
    """(channel id, log time, CDR bytes) of the Message records in ``data`` (and nothing else)."""
    out, pos, data = [], 0, memoryview(data)  # the C log hands its buffer over, not bytes
    while pos < len(data):
        opcode, length, cid, seq, t, pub = MESSAGE_HEADER.unpack_from(data, pos)
        assert opcode == 0x05 and seq == 0 and pub == t
        out.append((cid, t, bytes(data[pos + MESSAGE_HEADER.size : pos + 9 + length])))
        pos += 9 + length
    return out


def test_records_messages_counts_them_and_leaves_the_rest_to_the_fallback():
    refused = []
    log = new_log(lambda topic, msg: refused.append((topic, msg)))
    log.add("cyan/1/VelCmd", 3, "simatch_msgs/msg/VelCmd")
    log.add("model_states", 4, "simatch_msgs/msg/ModelStates")
    log.now = 7_000_000
    vel = msgs.new(msgs.VelCmd, stamp=0.007, tick=1, vx=1.5, w=-0.25)
    states = msgs.new(
        msgs.ModelStates,
        stamp=0.007,
        step=1,
        name=["ball"],
        pose=np.arange(7.0, dtype=np.float32),
        twist=np.ones(6, dtype=np.float32),
    )
    log("cyan/1/VelCmd", vel)
    log("model_states", states)
    log("cyan/1/Unknown", vel)  # not added: the fallback's
    listed = msgs.new(msgs.ModelStates, name=["ball"], pose=[1.0, 2.0], twist=np.zeros(0))
    log("model_states", listed)  # a list: converted or left to the fallback
    bad = msgs.new(msgs.VelCmd, vx="fast")
    log("cyan/1/VelCmd", bad)  # does not encode: the fallback's
    data, counts, first, last = log.take()
    records = _records(data)
    assert records[:2] == [(3, 7_000_000, msgs.encode(vel)), (4, 7_000_000, msgs.encode(states))]
    assert ("cyan/1/Unknown", vel) in refused and ("cyan/1/VelCmd", bad) in refused
    if ("model_states", listed) not in refused:  # the Python log converts lists itself
        assert records[2] == (4, 7_000_000, msgs.encode(listed))
    assert counts == {3: 1, 4: len(records) - 1} and first == last == 7_000_000
    assert log.size == 0
    empty, *rest = log.take()
    assert bytes(empty) == b"" and len(empty) == 0 and rest == [{}, -1, -1]


def test_clock_messages_set_the_time_and_end_chunks():
    log = new_log(lambda topic, msg: None)
    chunks = []
    log.add("clock", 1, "simatch_msgs/msg/Clock", CLOCK_STEP | CLOCK_TICK)
    log.add("model_states", 2, "simatch_msgs/msg/ModelStates", CLOCK_STEP)
    log.add("cyan/1/VelCmd", 3, "simatch_msgs/msg/VelCmd")
    log.timing(5_000_000, 500_000_000, lambda: chunks.append(log.take()))
    for step in range(0, 230):
        if step % 5 == 0:
            log("clock", msgs.new(msgs.Clock, stamp=step * 0.005, step=step, tick=step // 5))
        log(
            "model_states",
            msgs.new(
                msgs.ModelStates,
                step=np.uint64(step),
                name=[],
                pose=np.zeros(0, dtype=np.float32),
                twist=np.zeros(0, dtype=np.float32),
            ),
        )
        log("cyan/1/VelCmd", msgs.new(msgs.VelCmd, tick=step))
    assert log.now == 229 * 5_000_000
    assert [(first, last) for _, _, first, last in chunks] == [(0, 495_000_000), (500_000_000, 995_000_000)]
    assert chunks[0][1] == {1: 20, 2: 100, 3: 100}
    times = [t for _, t, _ in _records(chunks[1][0])]
    assert times == sorted(times) and times[0] == 500_000_000  # the step's clock opens the chunk
    data, counts, first, last = log.take()
    assert (first, last) == (1_000_000_000, 1_145_000_000) and counts == {1: 6, 2: 30, 3: 30}


def test_encoded_messages_and_raw_records():
    log = new_log(lambda topic, msg: None)
    log.now = 42
    log.append(b"raw")
    log.record(9, b"\x00\x01\x00\x00abc")
    with pytest.raises(ValueError):
        log.record(70000, b"x")
    data, counts, first, last = log.take()
    data = bytes(data)  # (a copy of the buffer the log hands over)
    assert data[:3] == b"raw" and _records(data[3:]) == [(9, 42, b"\x00\x01\x00\x00abc")]
    assert counts == {9: 1} and first == last == 42


def test_the_log_writes_ros_2s_clock_after_each_clock_message():
    """``ros_clock``: ROS 2's /clock at the time of each clock message's step, right after it, for a channel
    added before or after; a time beyond int32 seconds is not written (nothing a run does can stop on it)."""
    from simatch.record.layout import ros_clock

    refused = []
    log = new_log(lambda topic, msg: refused.append(msg.step))
    log.add("clock", 1, "simatch_msgs/msg/Clock", CLOCK_STEP | CLOCK_TICK)
    log.ros_clock("clock", 7)
    log.add("model_states", 2, "simatch_msgs/msg/ModelStates", CLOCK_STEP)
    log.timing(5_000_000, 500_000_000, lambda: None)
    states = msgs.new(msgs.ModelStates, step=3, name=[], pose=np.zeros(0, np.float32), twist=np.zeros(0, np.float32))
    log("model_states", states)  # sets the time, no clock of ROS 2
    tick = msgs.new(msgs.Clock, stamp=1.0, step=200_001, tick=40_000)
    log("clock", tick)
    log.now = 2**31 * 1_000_000_000  # beyond int32 seconds
    log.ros_clock("clock", 8)
    log("clock", msgs.new(msgs.Clock, step=-1))  # no time of its own (nor an encoding: the fallback's)
    records = _records(log.take()[0])
    assert [(cid, t) for cid, t, _ in records] == [(2, 15_000_000), (1, 1_000_005_000_000), (7, 1_000_005_000_000)]
    assert records[2][2] == ros_clock(1_000_005_000_000)
    assert records[1][2] == msgs.encode(tick)
    log.now = 61_500_000_000
    log("clock", msgs.new(msgs.Clock, step=-1))  # the fallback's, and ROS 2's clock after it all the same
    assert _records(log.take()[0]) == [(8, 61_500_000_000, ros_clock(61_500_000_000))]
    assert refused == [-1, -1]


def _memo_traffic() -> list[tuple[str, object]]:
    """Messages as a recorder meets them, for the memo: messages logged alone and met again in a team's list in
    the same memo period, the next one and the one after (forgotten by then), lists shared by many messages
    and by later periods, hundreds of entries per period (more than a first table holds)."""
    names = ["ball", "cyan/1", "magenta/1"]
    earlier: list[list] = []
    out: list[tuple[str, object]] = []
    for tick in range(6):
        out.append(("clock", msgs.new(msgs.Clock, stamp=tick * 0.025, step=5 * tick, tick=tick)))
        infos = [
            msgs.new(
                msgs.StrategyInfo, tick=tick, agent_id=i % 5 + 1, target_x=0.5 * i, user=np.arange(i % 3, dtype=float)
            )
            for i in range(150)
        ]
        out += [("cyan/1/StrategyInfo", info) for info in infos]
        for back in range(min(3, len(earlier) + 1)):  # this period's, the last one's, the one before
            team = infos[:5] if back == 0 else earlier[-back][3:9]
            out.append(("cyan/TeamStrategy", msgs.new(msgs.TeamStrategy, tick=tick, strategies=team)))
        earlier.append(infos)
        robots = [msgs.new(msgs.RobotInfo, id=i, x=0.1 * i, wheel_speeds=np.ones(3, np.float32)) for i in range(5)]
        for rid in range(1, 6):
            out.append(
                (
                    f"cyan/{rid}/OmniVisionInfo",
                    msgs.new(msgs.OmniVisionInfo, tick=tick, robot_id=rid, robots=robots),
                )
            )
        pose = np.arange(21, dtype=np.float32) * tick
        states = msgs.new(msgs.ModelStates, step=5 * tick, name=names, pose=pose, twist=np.zeros(18, np.float32))
        out.append(("model_states", states))
    return out


def test_what_the_memo_gives_again_is_what_encoding_gives():
    """Every record of what the memo serves (lists and messages met again) holds the bytes of encoding the
    message on its own, in the C log (whose memo is its own tables) and in the Python one."""
    log = new_log(lambda topic, msg: pytest.fail(f"{topic} went to the fallback"))
    traffic = _memo_traffic()
    channels: dict[str, int] = {}
    for topic, msg in traffic:
        if topic not in channels:
            channels[topic] = len(channels) + 1
            clock = CLOCK_STEP | CLOCK_TICK if topic == "clock" else CLOCK_STEP if topic == "model_states" else 0
            log.add(topic, channels[topic], msg.__msgtype__, clock)
        log(topic, msg)
    records = _records(log.take()[0])
    assert [(cid, data) for cid, _, data in records] == [(channels[t], msgs.encode(m)) for t, m in traffic]


def test_odd_but_valid_messages_are_recorded_as_rosbags_writes_them(tmp_path):
    """Lists for arrays, numpy scalars, an equal dtype object of its own: what the C encoder does not take as
    it is goes through the Python encoder, and every record holds rosbags' bytes."""
    import copy

    bus = InProcessBus()
    with simatch.Simulation("omni_circle") as sim:
        scene = sim.scene
    path = tmp_path / "odd.mcap"
    own = copy.deepcopy(np.dtype("<f8"))
    pose = np.arange(14.0)
    pairs = [
        (
            msgs.new(
                msgs.ModelStates, stamp=0.0, step=0, name=("a", "b"), pose=pose.tolist(), twist=np.arange(24.0)[::2]
            ),
            msgs.new(
                msgs.ModelStates,
                stamp=0.0,
                step=0,
                name=["a", "b"],
                pose=pose.astype(np.float32),
                twist=np.arange(0.0, 24.0, 2.0, dtype=np.float32),
            ),
        ),
        (
            msgs.new(
                msgs.ModelStates,
                stamp=np.float32(0.5),
                step=np.uint64(1),
                name=["a"],
                pose=np.arange(7.0).astype(own),
                twist=np.ones(6, dtype=">f8"),
            ),
            msgs.new(
                msgs.ModelStates,
                stamp=0.5,
                step=1,
                name=["a"],
                pose=np.arange(7.0, dtype=np.float32),
                twist=np.ones(6, dtype=np.float32),
            ),
        ),
        (
            msgs.new(msgs.StrategyInfo, role=np.int64(3), target_num=[1, 2], user=np.arange(3, dtype=np.float32)),
            msgs.new(msgs.StrategyInfo, role=3, target_num=np.array([1, 2], dtype=np.int32), user=np.arange(3.0)),
        ),
    ]
    assert pairs[1][0].pose.dtype is own
    with Recorder(bus, path, scene=scene, seed=0, dt=0.005):
        states, info = (
            bus.publisher("model_states", msgs.ModelStates),
            bus.publisher("cyan/1/StrategyInfo", msgs.StrategyInfo),
        )
        for m, _ in pairs:
            (info if m.__msgtype__.endswith("StrategyInfo") else states).put(m)
    got = [bytes(d) for topic, _, d in Recording(path).raw() if not topic.startswith("scene/")]
    assert got == [bytes(msgs.typestore.serialize_cdr(m, m.__msgtype__)) for _, m in pairs]


def test_a_clock_message_with_an_absurd_step_does_not_move_the_time():
    """A remote process may publish anything on a clock topic: a step that is no step, or whose time does not
    fit the log's 64 bits, leaves the time where it is; the message is still recorded."""
    log = new_log(lambda topic, msg: None)
    log.add("clock", 1, "simatch_msgs/msg/Clock", CLOCK_STEP | CLOCK_TICK)
    log.timing(5_000_000, 500_000_000, lambda: None)
    log("clock", msgs.new(msgs.Clock, step=40))
    log("clock", msgs.new(msgs.Clock, step=2**63 + 5))
    log("clock", msgs.new(msgs.Clock, step=2**62))
    assert log.now == 200_000_000
    assert [t for _, t, _ in _records(log.take()[0])] == [200_000_000] * 3


def test_the_pose_template_writes_each_scene_update_as_the_scene_builder_does():
    """Every 10th physics step of the model states, the log writes the 3D scene's game update itself; what
    its template does not take (no template yet, other models, poses that are no float buffer, too few rows)
    goes to the fallback, which sets a new template or says what is wrong. The log's bytes are the scene
    builder's, orientations and snapping included."""
    from simatch.config.loader import load_scene
    from simatch.record.scene3d import GRID, TURN_GRID, SceneBuilder

    builder = SceneBuilder(load_scene("msl_5v5").spec)
    log = new_log(lambda topic, msg: None)
    log.add("model_states", 2, "simatch_msgs/msg/ModelStates", CLOCK_STEP)
    log.timing(5_000_000, 500_000_000, lambda: None)
    handed, refused = [], []

    def fallback(msg):
        handed.append(int(msg.step))
        try:
            template, slots = builder.template(list(msg.name))
            log.pose_template(list(msg.name), template, slots, GRID, TURN_GRID)
            log.record(7, builder.game_update(list(msg.name), np.asarray(msg.pose, dtype=float).reshape(-1, 7)))
        except ValueError:
            refused.append(int(msg.step))

    log.poses("model_states", 7, 10, fallback)
    rng = np.random.default_rng(5)
    three, two = ["ball", "cyan/1", "magenta/2"], ["ball", "cyan/1"]
    expected = []
    for step in range(56):
        names = three if step < 25 else two
        yaw = rng.uniform(-3.2, 3.2, len(names))
        pose = (
            np.column_stack(
                [rng.uniform(-9, 9, (len(names), 3)), np.cos(yaw / 2), np.zeros((len(names), 2)), np.sin(yaw / 2)]
            )
            .astype(np.float32)
            .ravel()
        )
        if step == 40:
            pose = pose.astype(np.float64).tolist()  # a list: the fallback's
        if step == 50:
            pose = pose[:7]  # one row for two models: refused
        log(
            "model_states",
            msgs.new(
                msgs.ModelStates,
                step=step,
                name=list(names),
                pose=pose,
                twist=np.zeros(6 * len(names), dtype=np.float32),
            ),
        )
        if step % 10 == 0 and step != 50:
            expected.append(
                (step * 5_000_000, builder.game_update(names, np.asarray(pose, dtype=float).reshape(-1, 7)))
            )
    scene = [(t, data) for cid, t, data in _records(log.take()[0]) if cid == 7]
    assert scene == expected
    assert handed == [0, 30, 40, 50] and refused == [50]


def test_the_pose_template_refuses_slots_outside_it():
    log = new_log(lambda topic, msg: None)
    with pytest.raises(ValueError):
        log.pose_template(["ball"], b"\x00" * 64, [(4, 0, 0.0, False)], 1024.0, 4096.0)  # poses() first
    log.poses("model_states", 7, 10, lambda msg: None)
    for slots in ([(10, 0, 0.0, False)], [(2, 0, 0.0, False)], [(4, -1, 0.0, False)]):
        with pytest.raises(ValueError):
            log.pose_template(["ball"], b"\x00" * 64, slots, 1024.0, 4096.0)
    with pytest.raises(ValueError):
        log.pose_template(["ball"], b"\x00" * 64, [(4, 0, 0.0, False)], 0.0, 4096.0)


def test_a_taken_chunk_is_the_logs_buffer_and_stays_whole():
    """``take`` hands the buffer over without a copy; a chunk still held keeps its bytes while the log goes on,
    and the memory of a dropped one serves the next chunk with the right bytes."""
    log = new_log(lambda topic, msg: None)
    log.append(b"first" * 100_000)
    held = log.take()[0]
    log.append(b"second")
    assert bytes(held) == b"first" * 100_000 and len(memoryview(held)) == 500_000
    second = log.take()[0]
    assert bytes(second) == b"second"
    del held, second  # (the C log takes the larger buffer back for its next chunk)
    log.append(b"third")
    third = log.take()[0]
    assert bytes(third) == b"third" and len(third) == 5 and bytes(memoryview(third)[1:3]) == b"hi"


def test_a_chunk_goes_into_the_memory_lent_to_the_log():
    """``into``: a chunk's records go into the memory given (shared with the writer process); ``take`` hands a
    view of it over, with the bytes the log writes without it; the log writes no more into it once taken; a
    chunk that outgrows it is handed over as without it; read-only memory is refused."""
    memory = mmap.mmap(-1, 3 * 4096)
    slots = [memoryview(memory)[i * 4096 : (i + 1) * 4096] for i in range(3)]
    lent, plain = new_log(lambda topic, msg: None), new_log(lambda topic, msg: None)
    for log in (lent, plain):
        log.add("cyan/1/VelCmd", 3, "simatch_msgs/msg/VelCmd")
        log.now = 5_000_000
        log.append(b"held")  # before `into`: moved into the lent memory
    lent.into(slots[0])
    for tick in range(20):
        for log in (lent, plain):
            log("cyan/1/VelCmd", msgs.new(msgs.VelCmd, tick=tick, vx=0.5 * tick))
    # written there as they come
    assert bytes(slots[0][:4]) == b"held" and len(_records(bytes(slots[0][4 : 4 + plain.size - 4]))) == 20
    data, counts, first, last = lent.take()
    assert isinstance(data, memoryview) and data.obj is memory and bytes(data) == bytes(slots[0][: len(data)])
    expected, *rest = plain.take()
    assert bytes(data) == bytes(expected) and [counts, first, last] == rest
    before = bytes(memory)
    lent("cyan/1/VelCmd", msgs.new(msgs.VelCmd, tick=99))
    lent.append(b"x" * 5000)  # more than a slot
    assert bytes(memory) == before  # taken: not written into again
    lent.into(slots[1])  # what is held does not fit: it stays the log's own
    lent.append(b"y")
    big = lent.take()[0]
    assert not isinstance(big, memoryview) and bytes(big)[-5001:] == b"x" * 5000 + b"y" and bytes(memory) == before
    lent.into(slots[2])
    lent.append(b"z" * 3000)
    lent.append(b"z" * 3000)  # outgrows the slot while it is filled
    grown = lent.take()[0]
    assert not isinstance(grown, memoryview) and bytes(grown) == b"z" * 6000
    lent.into(slots[1])
    lent.append(b"own")
    lent.into(None)  # given back before the take: the records move to the log's own memory
    own = lent.take()[0]
    assert not isinstance(own, memoryview) and bytes(own) == b"own"
    for refused in (b"read-only", memoryview(bytearray(8))[::2]):
        with pytest.raises(BufferError):
            lent.into(refused)


def test_the_logs_callable_for_a_topic_logs_as_the_log_does():
    """``for_topic(topic)(msg)`` is ``log(topic, msg)``: the fallback's before the topic is added, its channel
    once added, the new one when it is added again (the C log finds the channel once per change)."""
    refused = []
    fallback = lambda topic, msg: refused.append((topic, msg.tick))  # noqa: E731
    log, plain = new_log(fallback), new_log(lambda topic, msg: None)
    vel = log.for_topic("cyan/1/VelCmd")
    vel(msgs.new(msgs.VelCmd, tick=1))
    assert refused == [("cyan/1/VelCmd", 1)] and log.size == 0
    for channel in (3, 4):
        for each in (log, plain):
            each.add("cyan/1/VelCmd", channel, "simatch_msgs/msg/VelCmd")
        for tick in range(2, 5):
            msg = msgs.new(msgs.VelCmd, tick=tick, vx=0.25 * tick)
            vel(msg)
            plain("cyan/1/VelCmd", msg)
    got, counts, *_ = log.take()
    expected, *rest = plain.take()
    assert bytes(got) == bytes(expected) and counts == {3: 3, 4: 3} == rest[0]
    with pytest.raises(TypeError):
        vel()
