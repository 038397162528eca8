"""`simatch COMMAND --help` is read in a terminal: plain text, no reStructuredText or Markdown markup, and it says
what each command takes."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys

import pytest

from simatch.cli import SUBCOMMANDS, build_parser

MARKUP = re.compile(r"``|`[^`\s][^`]*`|:(func|class|mod|meth|attr|ref):")


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_every_command_has_help():
    assert sorted(_subparsers()) == sorted(name.rsplit(".", 1)[1] for name in SUBCOMMANDS)


@pytest.mark.parametrize("command", sorted(name.rsplit(".", 1)[1] for name in SUBCOMMANDS))
def test_help_is_plain_text(command):
    text = _subparsers()[command].format_help()
    found = MARKUP.search(text)
    assert found is None, f"simatch {command} --help shows markup: {found.group(0)!r}"


def test_coach_help_in_a_terminal_is_plain_text():
    out = subprocess.run(
        [sys.executable, "-m", "simatch", "coach", "--help"], capture_output=True, text=True, timeout=60, check=True
    ).stdout
    assert "``" not in out and "simatch coach SCENE" not in out
    assert "--referee" in out and "Type 'help' at the prompt" in out


def test_serve_help_says_it_takes_a_recording():
    text = _subparsers()["serve"].format_help()
    usage = text.split("\n\n")[0]
    assert "FILE.mcap" in usage, usage
    assert "a recording" in text.split("positional arguments:")[1].split("options:")[0]
