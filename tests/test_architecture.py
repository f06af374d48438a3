"""Import rules from the design: sim and league never pull in textual; torch only where a
policy is trained or run, so the headless paths start fast."""

from __future__ import annotations

import ast
import importlib
import json
import pkgutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import grimp

import league
import sim

# Modules that train or run a policy may import torch; nothing else may.
TORCH_ALLOWED = {
    # A DeepRacer car archive's frozen graph, run with torch (the readers stay torch-free).
    "sim.car_archive.driver",
    # Writes a trained policy's tensors as the car's graph.
    "sim.car_export.export",
    "sim.car_archive.graph_runner",
    "sim.car_archive.policy",
    "sim.training.checkpoint",
    "sim.training.policy",
    # A trained policy as a race driver, its numpy actor and its runtimes (torch loads them).
    "sim.training.policy_driver",
    "sim.training.numpy_policy",
    "sim.training.runtimes",
    "sim.training.ppo",
    # A training's acting, in the trainer and in a camera model's simulation processes.
    "sim.training.actor",
    # The PPO update's loss, over SB3's distributions.
    "sim.training.ppo_loss",
    # The update's minibatches in shares, one thread each.
    "sim.training.minibatch_shares",
    # The learner's side of a fleet over processes (its parts, fleet_parts, stay light).
    "sim.training.shards",
    "sim.training.trainer",
    "sim.training.vec_env",
}


def _modules(package: object) -> list[str]:
    path = package.__path__  # type: ignore[attr-defined]
    prefix = package.__name__ + "."  # type: ignore[attr-defined]
    return sorted(info.name for info in pkgutil.walk_packages(path, prefix))


def _import_report(modules: list[str]) -> dict[str, list[str]]:
    """Import modules one at a time in a fresh interpreter, noting heavy imports after each."""
    script = f"""
import importlib, json, sys
report = {{}}
for name in {modules!r}:
    importlib.import_module(name)
    report[name] = sorted(m for m in ("textual", "torch", "stable_baselines3") if m in sys.modules)
print(json.dumps(report))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    return dict(json.loads(out.stdout))


def test_sim_and_league_never_import_textual_or_torch_outside_policy_modules() -> None:
    names = _modules(sim) + _modules(league)
    ordinary = [n for n in names if n not in TORCH_ALLOWED and ".reward.templates" not in n]
    report = _import_report(ordinary)
    assert report, "no modules were imported"
    offenders = {name: heavy for name, heavy in report.items() if heavy}
    assert offenders == {}


def test_headless_cli_does_not_import_textual_or_torch() -> None:
    report = _import_report(
        ["racer_tui.cli.main", "racer_tui.cli.track_commands", "racer_tui.cli.reward_commands"]
    )
    assert all(heavy == [] for heavy in report.values()), report


def test_the_app_module_is_the_one_that_imports_textual() -> None:
    report = _import_report(["racer_tui.app.application"])
    assert "textual" in report["racer_tui.app.application"]


def test_every_screen_uses_the_compact_aware_footer() -> None:
    # Textual's own Footer cuts a section's keys off at 80 columns; RacerFooter does not.
    import racer_tui.app.screens

    screens = Path(racer_tui.app.screens.__file__).parent
    plain = [
        path.name for path in sorted(screens.glob("*.py")) if "yield Footer(" in path.read_text()
    ]
    assert plain == []


def test_the_cli_knows_which_module_owns_each_subcommand() -> None:
    """`racer-tui CMD` imports only CMD's module, found in cli.COMMAND_MODULES."""
    import importlib

    from racer_tui.cli.main import COMMAND_MODULES

    for name, owned in COMMAND_MODULES.items():
        assert tuple(importlib.import_module(name).NAMES) == owned, name


def _imported_by(graph: grimp.ImportGraph, module: str) -> Iterator[str]:
    return iter(sorted(graph.find_modules_directly_imported_by(module)))


def _import_circles(graph: grimp.ImportGraph) -> list[list[str]]:
    """Groups of modules that import each other, directly or round a loop (Tarjan's
    strongly connected components, iteratively: the graph has thousands of edges)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    circles: list[list[str]] = []
    for root in sorted(graph.modules):
        if root in index:
            continue
        work = [(root, _imported_by(graph, root))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            module, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append(
                        (child, iter(sorted(graph.find_modules_directly_imported_by(child))))
                    )
                elif child in on_stack:
                    low[module] = min(low[module], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[module])
            if low[module] == index[module]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == module:
                        break
                if len(group) > 1:
                    circles.append(sorted(group))
    return circles


def test_no_import_circle() -> None:
    # grimp reads every import statement, those inside functions included: a circle hidden
    # behind a function-level import still counts.
    graph = grimp.build_graph("racer_tui", "league", "sim", "tracks", cache_dir=None)
    assert _import_circles(graph) == []


def test_the_circle_finder_finds_a_circle() -> None:
    graph = grimp.ImportGraph()
    for module in ("a", "a.one", "a.two", "a.three", "a.alone"):
        graph.add_module(module)
    graph.add_import(importer="a.one", imported="a.two")
    graph.add_import(importer="a.two", imported="a.three")
    graph.add_import(importer="a.three", imported="a.one")
    graph.add_import(importer="a.alone", imported="a.one")
    assert _import_circles(graph) == [["a.one", "a.three", "a.two"]]


# Errors that never reach a person: a malformed line between the training worker and the
# app, YAML's own error type that strict YAML extends (its caller words the sentence), and
# what the monkey finds broken in the app (for the benchmark's report).
NOT_FOR_PEOPLE = {
    "sim.training.events.EventError",
    "sim.foundation.strict_yaml.DuplicateKeyError",
    "racer_tui.app.monkey.InvariantError",
    # Control flow inside one module, each caught there and said in its own words.
    "sim.foundation.untrusted_tar.UnsafeMemberError",
    "sim.garage.model_archive._ScannedEnoughError",
    "sim.reward.droa_rules._ChainError",
    "sim.reward.droa_rules._DroaImportError",
}


def _error_classes() -> Iterator[tuple[str, str]]:
    """(module, class) for every class of the product named like an error."""
    for root in ("racer_tui", "sim", "league"):
        for path in sorted(Path(root).rglob("*.py")):
            module = ".".join(path.with_suffix("").parts).removesuffix(".__init__")
            for node in ast.parse(path.read_text(encoding="utf-8")).body:
                if isinstance(node, ast.ClassDef) and node.name.endswith(("Error", "Unavailable")):
                    yield module, node.name


def test_every_user_error_derives_from_the_one_root() -> None:
    from sim.foundation.remedies import RemedyError

    found = list(_error_classes())
    assert len(found) > 30  # the walk found the product's errors
    strays = [
        f"{module}.{name}"
        for module, name in found
        if f"{module}.{name}" not in NOT_FOR_PEOPLE
        and not issubclass(getattr(importlib.import_module(module), name), RemedyError)
    ]
    assert strays == []


def test_every_league_command_has_a_handler_module_that_runs_it() -> None:
    from racer_tui.cli import league_commands

    assert set(league_commands.HANDLER_MODULES) == set(league_commands.NAMES)
    for module in set(league_commands.HANDLER_MODULES.values()):
        handlers = importlib.import_module(f"racer_tui.cli.league_commands.{module}")
        assert callable(handlers.run)


def test_imports_inside_functions_stay_few_and_each_says_why() -> None:
    # ruff's PLC0415 refuses one without its noqa; each noqa carries its reason.
    lazy = [
        line
        for root in ("racer_tui", "sim", "league")
        for path in Path(root).rglob("*.py")
        for line in path.read_text(encoding="utf-8").splitlines()
        if "noqa: PLC0415" in line
    ]
    assert 0 < len(lazy) < 60
    assert all("noqa: PLC0415 (" in line and line.rstrip().endswith(")") for line in lazy)
