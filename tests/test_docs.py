"""The README and docs/architecture.md say what the code is: each claim they make that the code can settle is
settled here (the scenario count, what the referee does not judge, the paths the architecture names, the
performance targets)."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

from simatch.cli.bench import TARGETS
from simatch.config.schema import MatchSpec
from simatch.scene.referee.params import RULE_NAMES

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
ARCHITECTURE = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
SCENARIOS = ROOT / "tests" / "referee" / "scenarios"


def _section(text: str, heading: str) -> str:
    """The body of the ``## heading`` section (up to the next heading of the same level)."""
    return text.split(f"\n{heading}\n", 1)[1].split("\n## ", 1)[0]


def test_the_readme_states_how_many_referee_scenarios_there_are():
    claims = re.findall(r"(\d+) scenario files\s+\(`tests/referee/scenarios/", README)
    assert claims, "the README no longer states the number of referee scenario files"
    assert [int(n) for n in claims] == [len(list(SCENARIOS.glob("*.toml")))] * len(claims)


def not_judged(text: str) -> list[str]:
    """The items of the README's "Not judged (...): a; b; c." sentence, lower case, hyphens as spaces."""
    found = re.search(r"Not judged \([^)]*\)[^:]*:\s*(.*?)\.(?:\n\n|\n[A-Z#`]|$)", text, re.S)
    assert found, "the README no longer says what the referee does not judge"
    sentence = " ".join(found.group(1).split()).lower().replace("-", " ")
    return [re.sub(r"^(?:and |the |a |an )+", "", item.strip()) for item in re.split(r";|, and ", sentence)]


def test_the_readme_does_not_call_a_rule_the_referee_judges_not_judged():
    items = not_judged(README)
    phrases = {name: name.replace("_", " ") for name in RULE_NAMES}
    for item in items:
        for name, phrase in phrases.items():
            # a rule named as the item's subject, or a rule of several words named anywhere in it
            assert not item.startswith(phrase) and not (" " in phrase and phrase in item), (
                f"the README says {item!r} is not judged, but the referee has the rule {name!r}"
            )
        if MatchSpec.model_fields["change_ends"].default:
            assert "ends" not in item, f"the README says {item!r}, but the teams change ends by default"


def test_the_not_judged_check_catches_the_old_claims():
    old = (
        "Not judged (docs/referee.md says why): the ball-rotation\n"
        "part of ball holding, and teams do not change ends at half time.\n\n"
    )
    items = not_judged(old)
    assert items == ["ball rotation part of ball holding", "teams do not change ends at half time"]


def _resolve(path: str) -> bool:
    """Whether a path the architecture names exists: from the repository's root, from src/, or from
    src/simatch/ (the tree's own names)."""
    path = path.rstrip("/")
    return any(list(base.glob(path)) for base in (ROOT, ROOT / "src", ROOT / "src" / "simatch"))


def _resolve_dotted(name: str) -> bool:
    """Whether ``simatch.a.b.C`` (a module, or an attribute of one) exists."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        module = ".".join(parts[:cut])
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if found:
            obj = importlib.import_module(module)
            for attr in parts[cut:]:
                if not hasattr(obj, attr):
                    return False
                obj = getattr(obj, attr)
            return True
    return False


PATHLIKE = re.compile(r"^[\w./-]*/[\w./-]*$|^[\w/-]+\.(?:py|md|toml|c|msg|sh)$")


def architecture_paths(text: str) -> list[str]:
    """Every path the text names: in backticks (``src/simatch/sim/simulator.py``, ``sim/inputs.py``,
    ``tests/aerial/plugin_drone.py``), the entries of its tree of ``src/simatch/``, and the files and folders
    each entry's description names (``sight.py`` under ``sim/``: ``sim/sight.py``)."""
    named = [t for t in re.findall(r"`([^`\s]+)`", text) if PATHLIKE.match(t) and not t.startswith("simatch/<")]
    tree = text.split("```\nsrc/simatch/\n", 1)[1].split("```", 1)[0]
    for entry in re.split(r"\n(?=  \S)", tree.strip("\n")):
        name, _, description = entry.strip().partition(" ")
        named.append(name)
        for token in re.split(r"[\s(),;:`]+", description):
            if re.fullmatch(r"[\w*./-]+(?:/|\.(?:py|c|toml|md))", token) and not token.startswith("."):
                named.append(token if token.startswith(("tests/", "docs/")) or name.endswith(".py") else name + token)
    return named


def test_every_path_the_architecture_names_exists():
    paths = architecture_paths(ARCHITECTURE)
    assert len(paths) > 30 and "sim/" in paths and "robots/drive.py" in paths
    missing = [p for p in paths if not _resolve(p)]
    assert not missing, f"docs/architecture.md names paths that do not exist: {missing}"


def _top_level_parts() -> set[str]:
    """The packages and modules of src/simatch/ (``sim``, ``cli``, ``field``, ...)."""
    return {
        p.stem
        for p in (ROOT / "src" / "simatch").iterdir()
        if not p.name.startswith(("_", ".")) and (p.suffix == ".py" or (p / "__init__.py").exists())
    }


def test_every_module_the_architecture_names_exists():
    """``simatch.robots.quadrotor``, and names relative to the package: ``cli.run.EXTENSIONS``, ``msgs.f32``."""
    parts = _top_level_parts()
    dotted = re.findall(r"`((?:simatch\.)?[a-z_0-9]+(?:\.\w+)+)", ARCHITECTURE)
    names = sorted(
        {n if n.startswith("simatch.") else f"simatch.{n}" for n in dotted if n.split(".")[0] in parts | {"simatch"}}
    )
    assert len(names) > 10 and "simatch.cli.run.EXTENSIONS" in names
    missing = [n for n in names if not _resolve_dotted(n)]
    assert not missing, f"docs/architecture.md names modules that do not exist: {missing}"


def test_the_architecture_tree_lists_every_top_level_part():
    tree = ARCHITECTURE.split("```\nsrc/simatch/\n", 1)[1].split("```", 1)[0]
    listed = {m.group(1).rstrip("/").removesuffix(".py") for m in re.finditer(r"^  (\S+)", tree, re.M)}
    parts = _top_level_parts()
    assert parts == listed, f"not in the tree: {sorted(parts - listed)}; gone: {sorted(listed - parts)}"


@pytest.mark.parametrize("wrong", ["`sim/drive.py`", "`simatch/nowhere.py`"])
def test_the_path_check_catches_a_wrong_path(wrong):
    assert not all(_resolve(p) for p in architecture_paths(f"{wrong}\n```\nsrc/simatch/\n  sim/\n```\n"))


def performance_rows(text: str) -> dict[str, tuple[str, str]]:
    """The README's Performance table: figure -> (current, target)."""
    rows = {}
    for line in _section(text, "## Performance").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`"):
            rows[cells[0].split("`")[1]] = (cells[1], cells[2])
    return rows


def test_the_readme_performance_targets_are_the_bench_targets():
    rows = performance_rows(README)
    assert {"physics_rtf", "match_rtf", "record_match_wall_overhead_pct"} <= set(rows)
    for figure, (_, target) in rows.items():
        assert figure in TARGETS, f"the README gives {figure} a target, `simatch bench` has none"
        assert target == str(TARGETS[figure]), f"{figure}: README {target!r}, simatch bench {TARGETS[figure]}"


def test_the_target_check_catches_a_second_target():
    wrong = (
        "\n## Performance\n\n| figure | current | target | how |\n|---|---|---|---|\n| `match_rtf` | 83 | >= 30 | - |\n"
    )
    (_, target) = performance_rows(wrong)["match_rtf"]
    assert target != str(TARGETS["match_rtf"])


def test_a_target_says_whether_a_figure_meets_it():
    assert TARGETS["match_rtf"].met(80.0) and not TARGETS["match_rtf"].met(79.9)
    assert TARGETS["distributed_realtime_latency_p99_ms"].met(4.9)
    assert not TARGETS["distributed_realtime_latency_p99_ms"].met(5.0)


def test_simatch_bench_prints_each_figure_beside_its_target(monkeypatch, capsys):
    from types import SimpleNamespace

    from simatch.cli import bench

    monkeypatch.setattr(bench, "run_here", lambda name, seconds: {"match_rtf": 79.0, "match_sim_seconds": 120.0})
    assert bench.main(SimpleNamespace(only=["match"], json=False, seconds=None)) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(line.startswith("match_rtf") and line.endswith("(target >= 80: NOT met)") for line in lines), lines
    assert any(line.split() == ["match_sim_seconds", "120.0"] for line in lines), lines


def test_every_message_type_of_the_architecture_topics_is_defined():
    section = ARCHITECTURE.split("## Topics", 1)[1].split("\n## ", 1)[0]
    msg = ROOT / "src" / "simatch" / "msgs" / "simatch_msgs" / "msg"
    types = [
        t.strip() for line in section.splitlines() if line.startswith("| `") for t in line.split("|")[2].split(",")
    ]
    assert len(types) > 15
    missing = [t for t in types if not (msg / f"{t}.msg").exists()]
    assert not missing, f"docs/architecture.md's topics name message types that are not defined: {missing}"
