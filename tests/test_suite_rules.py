"""The suite's own rules: it stands on the repository alone and passes on any
machine that ran ./setup.sh.

- No test file reads a folder outside the repository (the metric reference
  vectors live in tests/data/reference/, not in a ``shared/`` beside the
  checkout, which a user's clone does not have).
- No test measures time: a speed claim is a benchmark (benchmarks/, tables
  of ratios), never a pass/fail on a clock, which fails under load.  Hang
  guards are left to pytest-timeout and to generous ``timeout=`` arguments
  of waits on other processes.
- No test skips or expects to fail: conftest.py turns a skip into a failure
  and pyproject.toml fails an empty parameter set at collection.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent
SOURCES = sorted(p for p in TESTS.rglob("*.py") if "__pycache__" not in p.parts)

#: a path into a folder beside the checkout, however it is spelled
OUTSIDE = re.compile(r"\.\./shared|shared/(reference|research|paper|DESIGN)|/\s*['\"]shared['\"]|"
                     r"parents\[\d\]\s*/\s*['\"]shared")
#: clocks a test could time code with
CLOCKS = {"time", "time_ns", "perf_counter", "perf_counter_ns", "monotonic", "monotonic_ns", "process_time",
          "process_time_ns", "thread_time", "thread_time_ns", "getrusage", "timeit", "default_timer"}
SKIPS = {"skip", "skipif", "xfail", "importorskip"}


def _calls(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            yield node.attr, node
        elif isinstance(node, ast.ImportFrom):
            for alias in node.names:
                yield alias.name, node


def rule_breaks(path: Path) -> list[str]:
    """What in ``path`` breaks the suite's rules, one line each (empty: none)."""
    text = path.read_text()
    found = [f"{path.name}:{n}: reads outside the repository: {line.strip()[:80]}"
             for n, line in enumerate(text.splitlines(), 1) if OUTSIDE.search(line)]
    tree = ast.parse(text)
    for name, node in _calls(tree):
        module = getattr(node, "module", None) or getattr(getattr(node, "value", None), "id", None)
        if name in CLOCKS and module in ("time", "resource", "timeit"):
            found.append(f"{path.name}:{node.lineno}: measures time ({module}.{name})")
        if name in SKIPS and module in ("pytest", "mark", "unittest"):
            found.append(f"{path.name}:{node.lineno}: skips or expects a failure ({name})")
    for node in ast.walk(tree):  # pytest.mark.skipif(...) and friends
        if isinstance(node, ast.Attribute) and node.attr in SKIPS and isinstance(node.value, ast.Attribute) \
                and node.value.attr == "mark":
            found.append(f"{path.name}:{node.lineno}: skips or expects a failure (mark.{node.attr})")
    return found


def test_no_test_reads_outside_the_repository_times_code_or_skips():
    assert len(SOURCES) > 50
    breaks = [b for p in SOURCES for b in rule_breaks(p)]
    assert not breaks, "\n".join(breaks)


def test_the_rules_catch_what_they_name(tmp_path):
    cases = {
        "beside.py": 'REF = REPO.parent / "{S}" / "reference"\n',
        "relative.py": 'p = "../{S}/reference/expected.json"\n',
        "clock.py": "import time\nt0 = time.perf_counter()\nassert time.perf_counter() - t0 < 5\n",
        "fromclock.py": "from time import monotonic\n",
        "rusage.py": "import resource\nr = resource.getrusage(resource.RUSAGE_CHILDREN)\n",
        "skip.py": "import pytest\npytest.skip('no data')\n",
        "skipif.py": "import pytest\n@pytest.mark.skipif(True, reason='x')\ndef test_x():\n    pass\n",
        "xfail.py": "import pytest\n@pytest.mark.xfail\ndef test_x():\n    pass\n",
    }
    for name, text in cases.items():
        (tmp_path / name).write_text(text.replace("{S}", "sha" + "red"))  # spelled out, this file would match
        assert rule_breaks(tmp_path / name), name
    (tmp_path / "fine.py").write_text("import time\ntime.sleep(0.1)\nshared = {}\nx = inputs.shared\n")
    assert rule_breaks(tmp_path / "fine.py") == []


def test_a_skip_fails_and_the_network_is_refused(tmp_path):
    """conftest.py's hooks, on a throwaway suite that uses them: a skip is reported as a
    failure and a connection beyond loopback is refused (loopback itself works)."""
    import shutil
    import subprocess
    import sys

    shutil.copy(TESTS / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_throwaway.py").write_text(
        "import socket\nimport pytest\n\n"
        "def test_skips():\n    pytest.skip('no data here')\n\n"
        "def test_reaches_out():\n"
        "    with pytest.raises(OSError, match='uses no network'):\n"
        "        socket.create_connection(('192.0.2.1', 80), timeout=1)\n\n"
        "def test_loopback():\n"
        "    server = socket.create_server(('127.0.0.1', 0))\n"
        "    with socket.create_connection(server.getsockname()):\n        pass\n"
        "    server.close()\n")
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                           "-p", "no:randomly", str(tmp_path)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert "1 failed, 2 passed" in proc.stdout, proc.stdout + proc.stderr
    assert "skipped, which this suite does not allow" in proc.stdout
