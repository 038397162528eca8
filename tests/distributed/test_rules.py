"""The rules of a distributed run, without a network: credentials and signatures, what a team may send, who
serves which robot, and the scene a team process rebuilds from the server's offer."""

from __future__ import annotations

import os
import stat

import pytest

from simatch import msgs
from simatch.config.loader import SceneError, load_scene
from simatch.distributed import credentials, protocol
from simatch.distributed.fairplay import FairPlay
from simatch.distributed.registry import JoinError, Proc, ProcState, Registry


@pytest.fixture
def creds(tmp_path):
    return credentials.ensure(tmp_path / "keys", ["cyan", "magenta", "admin"])


def test_credentials_are_private_stable_and_checked(tmp_path, creds):
    folder = tmp_path / "keys"
    assert stat.S_IMODE(os.stat(folder / "cyan.key").st_mode) == 0o600
    assert stat.S_IMODE(os.stat(folder).st_mode) == 0o700
    again = credentials.ensure(folder, ["cyan", "magenta", "admin"])
    assert again == creds  # kept across server runs
    (folder / "broken.key").write_text("cyan-no-secret\n")
    with pytest.raises(credentials.CredentialError, match="expected 'name:hexsecret'"):
        credentials.read(folder / "broken.key")
    with pytest.raises(credentials.CredentialError, match="does not exist"):
        credentials.read(folder / "nobody.key")
    users = credentials.users_file(folder, creds.values())
    assert sorted(open(users).read().split()) == sorted(f"{c.name}:{c.secret}" for c in creds.values())


def test_a_credential_appears_whole_or_not_at_all(tmp_path, monkeypatch):
    """A client reading while the server writes its keys never sees a half-written file: the key is written
    beside it and linked into place, leaving nothing else in the folder."""
    folder = tmp_path / "keys"
    seen = []
    real_link = os.link

    def link(src, dst):
        seen.append(os.path.exists(dst))  # the final name does not exist until the whole text is there
        assert open(src).read().count(":") == 1 and open(src).read().endswith("\n")
        real_link(src, dst)

    monkeypatch.setattr(os, "link", link)
    made = credentials.ensure(folder, ["cyan"])
    assert seen == [False]
    assert sorted(p.name for p in folder.iterdir()) == ["cyan.key"]
    assert credentials.read(folder / "cyan.key") == made["cyan"]


def test_signatures_prove_the_sender_for_this_run_topic_and_payload(creds):
    verify = credentials.Verifier("m1", creds)
    sign = creds["cyan"].signer("m1")
    data = msgs.encode(msgs.new(msgs.VelCmd, vx=1.0))
    att = sign("cyan/2/VelCmd", data)
    assert verify.signer_of("cyan/2/VelCmd", data, att) == "cyan"
    assert verify.signer_of("cyan/3/VelCmd", data, att) is None  # another topic
    assert verify.signer_of("cyan/2/VelCmd", data + b"x", att) is None  # another payload
    assert credentials.Verifier("m2", creds).signer_of("cyan/2/VelCmd", data, att) is None  # another run
    assert verify.signer_of("cyan/2/VelCmd", data, None) is None
    forged = att[:5] + b"magenta"[: att[4]] + att[5 + att[4] :]
    assert verify.signer_of("cyan/2/VelCmd", data, forged) is None
    stranger = credentials.Credential("cyan", "ab" * 32).signer("m1")
    assert verify.signer_of("cyan/2/VelCmd", data, stranger("cyan/2/VelCmd", data)) is None


def test_what_a_team_may_send(creds):
    fp = FairPlay("m1", creds, {"cyan": [1, 2, 3], "magenta": [1, 2, 3]})

    def check(who, topic, payload=b"\x00\x01\x00\x00"):
        return fp.check(topic, payload, creds[who].signer("m1")(topic, payload))

    for topic in ("cyan/2/VelCmd", "cyan/2/ActionCmd", "cyan/2/StrategyInfo", "cyan/TeamStrategy", "cyan/lockstep/ack"):
        assert check("cyan", topic) is None, topic
    refusal = check("cyan", "magenta/2/VelCmd")
    assert refusal.who == "cyan" and "may not command magenta/2" in refusal
    assert "has no robot 7" in check("cyan", "cyan/7/VelCmd")
    for topic in ("set_model_state", "set_link_state", "apply_wrench", "referee_command"):
        assert "only the organiser's admin credential" in check("cyan", topic)
        assert check("admin", topic) is None
    assert "may not publish on magenta/TeamStrategy" in check("cyan", "magenta/TeamStrategy")
    assert "may not publish on cyan/receive_from_coach" in check("cyan", "cyan/receive_from_coach")
    own = msgs.encode(msgs.new(msgs.GameEvent, type="strategy_error", team="cyan", robot=2))
    fake = msgs.encode(msgs.new(msgs.GameEvent, type="goal", team="cyan"))
    assert check("cyan", "events", own) is None
    assert "may log only its own strategy_error events" in check("cyan", "events", fake)
    assert "unsigned" in fp.check("cyan/2/VelCmd", b"x", None) and fp.check("cyan/2/VelCmd", b"x", None).who == ""
    # the verdicts are remembered per (sender, topic): asked again, the same answers (events stay per payload)
    assert (
        "may not command magenta/2" in check("cyan", "magenta/2/VelCmd")
        and check("magenta", "magenta/2/VelCmd") is None
    )
    assert check("cyan", "cyan/2/VelCmd") is None and check("cyan", "events", own) is None
    assert "may log only" in check("cyan", "events", fake)
    att = creds["cyan"].signer("m1")("cyan/lockstep/bundle", b"SMB1")
    assert fp.check_entry(att, "cyan/2/VelCmd", b"") is None and "may not command" in fp.check_entry(
        att, "magenta/1/VelCmd", b""
    )
    for k in range(10_000):  # a sender inventing topics cannot grow the memory
        fp.check_entry(att, f"cyan/x{k}", b"")
    assert len(fp._verdicts) <= 4096 and "has no robot 7" in fp.check_entry(att, "cyan/7/VelCmd", b"")


def test_access_control_lets_a_team_hear_only_its_own(creds):
    acl = FairPlay("m1", creds, {"cyan": [1], "magenta": [1]}).access_control()
    assert acl["enabled"] and acl["default_permission"] == "deny"
    rules = {r["id"]: r for r in acl["rules"]}
    hears = rules["cyan-hear"]["key_exprs"]
    assert "simatch/m1/cyan/*/OmniVisionInfo" in hears and "simatch/m1/lockstep/tick/*" in hears
    assert not any("magenta" in k or "model_states" in k for k in hears)
    assert rules["cyan-hear"]["messages"] == ["declare_subscriber"] and rules["cyan-hear"]["flows"] == ["ingress"]
    policies = {tuple(p["subjects"]): p["rules"] for p in acl["policies"]}
    assert all(r.startswith("cyan-") for r in policies[("cyan",)])


def test_who_serves_which_robot():
    reg = Registry(load_scene("msl_5v5").spec)
    assert reg.missing() == {"cyan": [1, 2, 3, 4, 5], "magenta": [1, 2, 3, 4, 5]}
    reg.join(Proc("a", "cyan", [1, 2, 3, 4, 5], "team", True, 0))
    with pytest.raises(JoinError, match="cyan/2 is already served by team process a"):
        reg.join(Proc("b", "cyan", [2], "robot", False, 0))
    with pytest.raises(JoinError, match="no robot"):
        reg.join(Proc("c", "magenta", [9], "robot", False, 0))
    with pytest.raises(JoinError, match="no team 'blue'"):
        reg.join(Proc("d", "blue", [1], "robot", False, 0))
    reg.procs["a"].state = ProcState.LATE  # a hung process is replaced by a restarted one
    reg.join(Proc("e", "cyan", [2], "robot", False, 0))
    assert reg.procs["a"].state is ProcState.GONE and reg.owner["cyan/2"] == "e"
    assert reg.missing() == {"cyan": [1, 3, 4, 5], "magenta": [1, 2, 3, 4, 5]}
    reg.leave("e")
    assert "cyan/2" not in reg.owner


def test_a_team_process_rebuilds_the_servers_scene_with_its_own_strategy():
    scene = load_scene("msl_5v5", {"ball.mass": 0.5, "teams.cyan.strategy": "external"})
    offer = protocol.loads(protocol.dumps(protocol.scene_offer(scene, 7, "m1", protocol.LOCKSTEP)), "scene")
    mine = protocol.scene_from_offer(offer, {"teams.cyan.strategy": "constant", "teams.cyan.strategy_params.vx": 1.0})
    assert mine.spec.ball.mass == 0.5 and mine.spec.teams["cyan"].strategy == "constant"
    assert mine.spec.teams["cyan"].strategy_params == {"vx": 1.0} and offer["seed"] == 7
    with pytest.raises(SceneError, match="unknown key"):
        protocol.scene_from_offer(offer, {"teams.cyan.strategy_paramz": 1})
    with pytest.raises(protocol.ProtocolError, match="missing"):
        protocol.loads(b'{"tick": 1}', "proc", "tick")
    with pytest.raises(protocol.ProtocolError, match="not JSON"):
        protocol.loads(b"\xff", "proc")


def test_the_ack_is_the_protocols_json():
    proc = protocol.new_proc_id()
    for tick, sent in ((0, 0.0), (12345, 98765.4321), (7, 1e-9)):
        raw = protocol.ack(proc, tick, sent)
        assert raw == protocol.dumps({"proc": proc, "tick": tick, "sent": sent})
        assert protocol.loads(raw, "proc", "tick", "sent") == {"proc": proc, "tick": tick, "sent": sent}
        raw = protocol.ack(proc, tick, sent, got=sent - 0.25)
        assert raw == protocol.dumps({"proc": proc, "tick": tick, "sent": sent, "got": sent - 0.25})
