"""Every referee scenario file (tests/referee/scenarios/*.toml) runs through the Python API and must come out
as it states: the calls it expects, with their measured values, and — in a legal case — no foul at all,
because a referee that flags a legal situation is as wrong as one that misses a foul."""

from __future__ import annotations

from collections import defaultdict

import pytest

from simatch.scene.referee.params import RULE_NAMES

from .scenario import all_scenarios

SCENARIOS = all_scenarios()


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[s.name for s in SCENARIOS])
def test_scenario(scenario):
    out = scenario.run()
    problems = scenario.check(out)
    assert not problems, "\n".join([scenario.data.get("description", ""), *problems, out.describe()])


def test_every_rule_has_a_legal_and_an_illegal_case():
    cases = defaultdict(set)
    for s in SCENARIOS:
        cases[s.rule].add(s.legal)
    missing = [rule for rule in RULE_NAMES if cases.get(rule) != {True, False}]
    assert not missing, f"rules without both a legal and an illegal scenario: {missing}"
    assert len(SCENARIOS) >= 30
