"""The bundle format: entries come back as packed, in order; anything broken is refused whole."""

from __future__ import annotations

import pytest

from simatch import msgs
from simatch.bus import bundle


def test_entries_come_back_in_order_with_their_types_and_bytes():
    vel = msgs.encode(msgs.new(msgs.VelCmd, vx=1.5, tick=7))
    entries = [
        ("cyan/2/VelCmd", "simatch_msgs/msg/VelCmd", vel),
        ("cyan/lockstep/ack", "", b'{"tick":7}'),
        ("émoji/ü", "", b""),
    ]
    out = bundle.unpack(bundle.pack(entries))
    assert [tuple(e) for e in out] == entries
    assert msgs.decode(msgs.VelCmd, out[0].payload).vx == 1.5
    assert bundle.unpack(bundle.pack([])) == []


@pytest.mark.parametrize(
    "data",
    [
        b"",
        b"SMB0",
        b"junk",
        b"SMB1\x05",
        b"SMB1\x05\x00abc",
        b"SMB1\x01\x00a\x00\x00\x10\x00\x00\x00short",
        b"SMB1\x02\x00\xff\xfe\x00\x00\x00\x00\x00\x00",
    ],
)
def test_a_broken_bundle_is_refused_whole(data):
    with pytest.raises(bundle.BundleError):
        bundle.unpack(data)


def test_every_truncation_is_refused_or_a_whole_prefix_of_entries():
    data = bundle.pack([("a/b", "t", b"xyz"), ("c", "", b"12345")])
    for k in range(len(data)):
        try:
            out = bundle.unpack(data[:k])
        except bundle.BundleError:
            continue
        assert [e.topic for e in out] in ([], ["a/b"])


def test_split_cuts_in_order_below_the_limit_and_sets_aside_what_fits_nowhere():
    entries = [(f"t/{k}", "", bytes(100 + k)) for k in range(10)] + [("big", "", bytes(5000))] + [("z", "", b"1")]
    runs, too_large = bundle.split(entries, 400)
    assert too_large == [("big", "", bytes(5000))]
    assert [e for run in runs for e in run] == entries[:10] + entries[11:]  # same order, nothing lost
    assert all(len(bundle.pack(run)) <= 400 for run in runs) and len(runs) > 1
    assert sum(map(bundle.size, entries[:2])) + len(bundle.MAGIC) == len(bundle.pack(entries[:2]))
    assert bundle.split([], 400) == ([], [])
