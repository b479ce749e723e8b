"""The package's dependencies run one way: params <- golden, hdl <- sim <- gen.

Read from the sources (the import statements), so that a new import against the
direction fails here rather than as a cycle later. Imports of npstereo modules inside
functions are not allowed either: they are how a cycle hides.
"""

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Which packages each package may import from.
ALLOWED = {
    "params": set(),
    "golden": {"params"},
    "hdl": {"params"},
    "sim": {"params", "golden", "hdl"},
    "gen": {"params", "golden", "hdl", "sim"},
}


def imported_packages(path):
    """(npstereo package, line, at module level) of every project import in ``path``."""
    tree = ast.parse(path.read_text())
    top_level = {id(node) for node in tree.body}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1:
                names = [path.parent.name]
            elif node.level == 2:
                names = [(node.module or "").split(".")[0]] if node.module else \
                    [alias.name for alias in node.names]
            elif (node.module or "").startswith("npstereo."):
                names = [node.module.split(".")[1]]
            else:
                continue
        elif isinstance(node, ast.Import):
            names = [a.name.split(".")[1] for a in node.names if a.name.startswith("npstereo.")]
        else:
            continue
        found += [(name, node.lineno, id(node) in top_level) for name in names]
    return found


def violations(package):
    problems = []
    for path in sorted((ROOT / package).glob("*.py")):
        for name, line, top in imported_packages(path):
            if name != package and name not in ALLOWED[package]:
                problems.append(f"{path.name}:{line} imports {name}")
            if not top:
                problems.append(f"{path.name}:{line} imports {name} inside a function")
    return problems


@pytest.mark.parametrize("package", list(ALLOWED))
def test_imports_follow_the_direction(package):
    assert violations(package) == []


def test_a_backward_import_is_caught(tmp_path, monkeypatch):
    """Broken variant: an hdl module importing the golden model is reported."""
    (tmp_path / "hdl").mkdir()
    (tmp_path / "hdl" / "bad.py").write_text("from ..golden.lr_check import INVALID\n"
                                            "def f():\n    from .core import NpStereoCore\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    assert violations("hdl") == ["bad.py:1 imports golden",
                                 "bad.py:3 imports hdl inside a function"]
