"""Credential files: waiting for the server to write them, and saying what is wrong when one never comes."""

from __future__ import annotations

import threading

import pytest

from simatch.distributed import credentials


def test_a_team_not_in_the_run_is_told_which_credentials_there_are(tmp_path):
    credentials.ensure(tmp_path, ["admin", "cyan", "magenta"])
    with pytest.raises(credentials.CredentialError) as err:
        credentials.await_file(tmp_path / "blue.key", wait=0.3, poll=0.05)
    text = str(err.value)
    assert "blue.key" in text and "admin, cyan, magenta" in text and "'blue'" in text
    assert "teams (cyan, magenta)" in text and "\n" not in text


def test_no_folder_yet_asks_whether_a_server_runs(tmp_path):
    with pytest.raises(credentials.CredentialError, match="is the server running"):
        credentials.await_file(tmp_path / "run" / "cyan.key", wait=0.2, poll=0.05)


def test_a_credential_written_while_waiting_is_taken(tmp_path):
    writer = threading.Timer(0.3, lambda: credentials.ensure(tmp_path, ["cyan"]))
    writer.start()
    try:
        cred = credentials.await_file(tmp_path / "cyan.key", wait=10.0, poll=0.05)
    finally:
        writer.join()
    assert cred.name == "cyan" and len(cred.key) == 32


def test_a_broken_file_is_refused_at_once(tmp_path):
    (tmp_path / "cyan.key").write_text("garbage")
    with pytest.raises(credentials.CredentialError, match="expected 'name:hexsecret'"):
        credentials.await_file(tmp_path / "cyan.key", wait=30.0)
