"""The house rules, checked on the source (ast), not by importing it:

- no import cycle anywhere in the package (imports inside functions count:
  a cycle hidden in a function is still a cycle);
- data flows one way: render -> optics -> sensor -> isp -> metrics -> study
  -> report (-> design), commands on top; io, spectra, values, colorimetry
  (with its compiled loops, colour_kernels),
  errors and the version are shared leaves that import no stage;
- no source file over 500 lines (package, tests, benchmarks);
- no test module hard-codes a registry's member list (the one rule that
  imports the package: the registries are filled when it loads); a test
  takes the members from the registry, the paper's sets from the paper's
  data, a config's from the config.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "cfa_mitsuba"

#: Stage order; a module may import its own stage, an earlier one, or a leaf.
STAGES = {"render": 1, "optics": 2, "sensor": 3, "isp": 4, "metrics": 5, "study": 6, "report": 7, "design": 8,
          "commands": 9, "cli": 9, "__main__": 9}
LEAVES = {"errors", "spectra", "values", "colorimetry", "colour_kernels", "colour_science", "_version", "io", "data"}


def _module_name(path: Path) -> str:
    rel = path.relative_to(REPO).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _resolve(mod: str, is_pkg: bool, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """{module: modules it imports} inside the package.  ``from X import Y``
    is an edge to X.Y when that is a module, else to X; the implicit import
    of parent packages is not an edge (every submodule would otherwise form a
    cycle with its package's ``__init__``)."""
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for mod, path in modules.items():
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(mod, is_pkg, node)
                for a in node.names:
                    full = f"{base}.{a.name}"
                    targets.append(full if full in modules else base)
            for t in targets:
                if t in modules and t != mod:
                    graph[mod].add(t)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules, or None (iterative DFS)."""
    state: dict[str, int] = {}
    for start in sorted(graph):
        if state.get(start):
            continue
        stack = [(start, iter(sorted(graph[start])))]
        path = [start]
        state[start] = 1
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                state[node] = 2
                stack.pop()
                path.pop()
            elif state.get(child) == 1:
                return path[path.index(child):] + [child]
            elif not state.get(child):
                state[child] = 1
                path.append(child)
                stack.append((child, iter(sorted(graph[child]))))
    return None


def _stage(mod: str):
    parts = mod.split(".")
    if len(parts) < 2:
        return None  # the package root (lazy attribute access only)
    top = parts[1]
    if top in LEAVES:
        return 0
    return STAGES.get(top)


def test_the_walker_finds_a_planted_cycle_and_a_backward_import():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}
    assert find_cycle(g) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None
    # the resolver maps relative imports as Python does
    node = ast.parse("from ..metrics import colour").body[0]
    assert _resolve("cfa_mitsuba.study.tasks", False, node) == "cfa_mitsuba.metrics"
    node = ast.parse("from . import records").body[0]
    assert _resolve("cfa_mitsuba.metrics", True, node) == "cfa_mitsuba.metrics"
    assert _stage("cfa_mitsuba.study.tasks") > _stage("cfa_mitsuba.metrics.ssim") > _stage("cfa_mitsuba.io.exr")


def test_no_import_cycle():
    graph = import_graph(_modules())
    assert len(graph) > 50
    cycle = find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_no_stage_imports_a_later_one():
    bad = []
    for mod, targets in import_graph(_modules()).items():
        mine = _stage(mod)
        if mine is None:
            continue
        for t in targets:
            theirs = _stage(t)
            if theirs is None:
                bad.append(f"{mod} -> {t} (a module outside the stage map)")
            elif theirs > mine or (mine == 0 and theirs != 0):
                bad.append(f"{mod} -> {t}")
    assert not bad, "backward stage imports:\n" + "\n".join(sorted(bad))


#: Stages the report may not import: it draws what a study wrote (results
#: files), never recomputes camera physics (a fit, a CFA, a readout).
REPORT_FORBIDDEN = ("render", "optics", "sensor", "isp")


def report_violations(graph: dict[str, set[str]]) -> list[str]:
    """``report.* -> {render, optics, sensor, isp}.*`` import edges."""
    bad = []
    for mod, targets in graph.items():
        if not mod.startswith("cfa_mitsuba.report"):
            continue
        bad += [f"{mod} -> {t}" for t in sorted(targets) if t.split(".")[1:2] and t.split(".")[1] in REPORT_FORBIDDEN]
    return bad


def test_the_report_reads_results_only():
    graph = import_graph(_modules())
    bad = report_violations(graph)
    assert not bad, "the report imports camera stages:\n" + "\n".join(bad)


def test_the_report_rule_catches_a_planted_import(tmp_path):
    """The rule above fails on a report module that imports sensor/ (inside a
    function too), isp/, optics/ or render/."""
    for stage in REPORT_FORBIDDEN:
        mods = _modules()
        planted = tmp_path / f"planted_{stage}.py"
        planted.write_text(f"def f():\n    from ..{stage} import something\n")
        mods["cfa_mitsuba.report.planted"] = planted
        graph = import_graph(mods)
        assert report_violations(graph) == [f"cfa_mitsuba.report.planted -> cfa_mitsuba.{stage}"], stage


def test_no_long_functions_in_study_and_report():
    """No function over 120 lines in study/ and report/ (long ones are split into named steps)."""
    long = []
    for folder in ("study", "report"):
        for p in (PACKAGE / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(p.read_text(), str(p))):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    n = node.end_lineno - node.lineno + 1
                    if n > 120:
                        long.append(f"{p.relative_to(REPO)}:{node.lineno} {node.name} ({n} lines)")
    assert not long, "functions over 120 lines:\n" + "\n".join(long)


@pytest.mark.parametrize("folder", ["cfa_mitsuba", "tests", "benchmarks"])
def test_no_source_file_over_500_lines(folder):
    long = [(str(p.relative_to(REPO)), n) for p in (REPO / folder).rglob("*.py")
            if (n := len(p.read_text().splitlines())) > 500]
    assert not long, f"files over 500 lines: {long}"


def test_the_render_cache_of_this_run_is_its_own():
    """conftest points the render cache at this run's temporary directory
    (fresh every run), unless CFA_MITSUBA_TEST_CACHE asks for another."""
    import os

    cache = Path(os.environ["CFA_MITSUBA_CACHE"])
    if os.environ.get("CFA_MITSUBA_TEST_CACHE"):
        assert cache == Path(os.environ["CFA_MITSUBA_TEST_CACHE"].strip())
        return
    assert cache.name == "cfa-mitsuba-test-cache"
    assert cache.parent.name.startswith("pytest-") and cache.parent.name[len("pytest-"):].isdigit(), cache
    assert cache.parent != Path.home() / ".cache"


def registry_members() -> dict[str, frozenset]:
    """{registry: the names of its members}: every registry a user adds to
    (metrics, with and without the values read from details, and the scored
    ones; demosaics, denoisers, sharpeners, CFAs, axes, scenes, sensor
    presets, spectra sets)."""
    import cfa_mitsuba as cm
    from cfa_mitsuba.isp.denoise import list_denoisers
    from cfa_mitsuba.isp.sharpen import list_sharpeners
    from cfa_mitsuba.study.axes import AXES

    found = {
        "metrics": cm.metrics.metric_names(), "metrics and values": cm.metrics.metric_names(secondary=True),
        "scored metrics": cm.metrics.scored_metrics(), "demosaics": [n for n, _ in cm.isp.list_demosaics()],
        "denoisers": [n for n, _ in list_denoisers()], "sharpeners": [n for n, _ in list_sharpeners()],
        "CFAs": cm.sensor.list_cfas(), "axes": list(AXES), "scenes": [n for n, _ in cm.render.list_scenes()],
        "sensor presets": cm.sensor.list_sensor_presets(), "spectra sets": cm.sensor.list_spectra_sets(),
    }
    return {k: frozenset(v) for k, v in found.items() if len(v) >= 3}


def hard_coded_member_lists(path: Path, members: dict[str, frozenset], root: Path = REPO) -> list[str]:
    """``file:line registry`` for each literal list, tuple, set or dict (its
    keys) of names that is a registry's whole member list: a test that
    spells one out breaks, or silently leaves the new member out, when a
    member is added."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
            items = node.elts
        elif isinstance(node, ast.Dict):
            items = node.keys
        else:
            continue
        names = {e.value for e in items if isinstance(e, ast.Constant) and isinstance(e.value, str)}
        if len(names) < 3 or len(names) != len(items):
            continue
        bad += [f"{path.relative_to(root)}:{node.lineno} {k}" for k, v in members.items() if names == v]
    return bad


def test_no_test_module_hard_codes_a_registry_member_list():
    members = registry_members()
    bad = [b for p in sorted((REPO / "tests").rglob("*.py")) for b in hard_coded_member_lists(p, members)]
    assert not bad, "test modules that spell out a registry's members:\n" + "\n".join(bad)


def test_the_member_list_rule_catches_a_planted_list(tmp_path):
    members = registry_members()
    demosaics = sorted(members["demosaics"])
    planted = tmp_path / "test_planted.py"
    planted.write_text(f"METHODS = {tuple(demosaics)!r}\nUNITS = {{{', '.join(f'{n!r}: 1' for n in demosaics)}}}\n"
                       f"SOME = {demosaics[:2]!r}\n")
    found = hard_coded_member_lists(planted, members, root=tmp_path)
    assert [f.split()[-1] for f in found] == ["demosaics", "demosaics"]  # the tuple and the dict, not the subset



def _string_constants(folder: Path) -> list[tuple[str, int, str]]:
    out = []
    for path in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                out.append((str(path.relative_to(REPO)), node.lineno, node.value))
    return out


def test_the_report_names_no_scene():
    """A scene's name comes from the results (its record), never from report/ code."""
    from cfa_mitsuba.render import list_scenes

    names = {name for name, _ in list_scenes()}
    bad = [f"{p}:{line} {v!r}" for p, line, v in _string_constants(PACKAGE / "report") if v in names]
    assert not bad, "report/ code that names a scene:\n" + "\n".join(bad)


def test_the_exposure_defaults_are_defined_once():
    """EXPOSURE_POLICIES is assigned in one module; the 1/30 s maximum exposure is written once."""
    assigned, thirtieths = [], []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
                node, ast.AnnAssign) else []
            if any(isinstance(t, ast.Name) and t.id == "EXPOSURE_POLICIES" for t in targets):
                assigned.append(f"{path.relative_to(REPO)}:{node.lineno}")
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and all(
                    isinstance(v, ast.Constant) for v in (node.left, node.right)) and (
                    node.left.value, node.right.value) in ((1, 30), (1.0, 30.0), (1, 30.0), (1.0, 30)):
                thirtieths.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert len(assigned) == 1, assigned
    assert len(thirtieths) == 1, thirtieths
