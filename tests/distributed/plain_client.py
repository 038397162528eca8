"""A robot or team process that speaks the protocol topic by topic, as a client in another language that
ignores bundles would (docs/distributed.md, "The protocol"): it subscribes to its tick and to each of its
topics, and sends each command and its ack as a sample of its own.

    python -m tests.distributed.plain_client TEAM[/ID] --connect ENDPOINT --run RUN --key FILE
"""

from __future__ import annotations

import argparse
import sys

from simatch.bus import topics
from simatch.distributed.client import TeamProcess


class PlainProcess(TeamProcess):
    """simatch's own client with the server's offer of bundles declined."""

    def _ask_scene(self) -> dict:
        offer = super()._ask_scene()
        offer.pop("bundles", None)
        return offer


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("who")
    p.add_argument("--connect", required=True)
    p.add_argument("--run", required=True)
    p.add_argument("--key", required=True)
    args = p.parse_args(argv)
    if "/" in args.who:
        team, rid = topics.split_robot_name(args.who)
        robots = [rid]
    else:
        team, robots = args.who, None
    proc = PlainProcess(team, robots, connect=args.connect, run=args.run, key=args.key, wait=60.0)
    reason = proc.run()
    assert not proc.bundles
    proc.say(f"{proc.what} (topic by topic): the server ended the run ({reason}) after {proc.ticks} ticks")
    return 0


if __name__ == "__main__":
    sys.exit(main())
