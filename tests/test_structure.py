"""The package's dependencies run one way: params <- golden, hdl <- sim <- gen.

Read from the sources (the import statements of every module, subpackages included), so
that a new import against the direction fails here rather than as a cycle later. Imports
of npstereo modules inside functions are not allowed either: they are how a cycle hides.
Neither are dynamic imports (``importlib.import_module``, ``__import__``), with one
exception: the command line's dispatcher (``gen/cli/main.py``) imports the module of the
command being run by name, so that a command does not load what only the others use.

Within ``gen/cli``, a command module (``cmd_*``) imports no other command module: what
several commands share lives in a module that is not a command.
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
#: The one module allowed a dynamic import, relative to ROOT.
DISPATCHER = Path("gen/cli/main.py")


def imported_modules(path):
    """(npstereo module, line, at module level) of every project import in ``path``, the
    module as the list of its names below ``npstereo`` (``["gen", "cli", "arguments"]``).

    ``from . import a, b`` names the modules ``a`` and ``b`` of the package.
    """
    tree = ast.parse(path.read_text())
    top_level = {id(node) for node in tree.body}
    package = list(path.relative_to(ROOT).parts[:-1])
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:max(0, len(package) - node.level + 1)]
                module = base + (node.module.split(".") if node.module else [])
            elif (node.module or "").startswith("npstereo."):
                module = node.module.split(".")[1:]
            else:
                continue
            modules = [module] if node.module else [module + [a.name] for a in node.names]
        elif isinstance(node, ast.Import):
            modules = [a.name.split(".")[1:] for a in node.names
                       if a.name.startswith("npstereo.")]
        else:
            continue
        found += [(module, node.lineno, id(node) in top_level) for module in modules]
    return found


def _sources(package):
    return sorted((ROOT / package).rglob("*.py"))


def _name(path, package):
    return path.relative_to(ROOT / package).as_posix()


def violations(package):
    problems = []
    for path in _sources(package):
        for module, line, top in imported_modules(path):
            name = module[0] if module else "npstereo"
            if name != package and name not in ALLOWED[package]:
                problems.append(f"{_name(path, package)}:{line} imports {name}")
            if not top:
                problems.append(f"{_name(path, package)}:{line} imports {name} inside a "
                                "function")
    return problems


def command_imports(package="gen"):
    """A command module (``cmd_*.py``) importing another command module."""
    problems = []
    for path in _sources(package):
        if not path.stem.startswith("cmd_"):
            continue
        for module, line, _ in imported_modules(path):
            if module and module[-1].startswith("cmd_") and module[-1] != path.stem:
                problems.append(f"{_name(path, package)}:{line} imports {'.'.join(module)}")
    return problems


def dynamic_imports(package):
    """Calls of ``importlib.import_module``/``import_module`` or ``__import__`` outside
    :data:`DISPATCHER`."""
    problems = []
    for path in _sources(package):
        if path.relative_to(ROOT) == DISPATCHER:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call):
                called = node.func.attr if isinstance(node.func, ast.Attribute) else \
                    getattr(node.func, "id", None)
                if called in ("import_module", "__import__"):
                    problems.append(f"{_name(path, package)}:{node.lineno} imports "
                                    "dynamically")
    return problems


@pytest.mark.parametrize("package", list(ALLOWED))
def test_imports_follow_the_direction(package):
    assert violations(package) == []


@pytest.mark.parametrize("package", list(ALLOWED))
def test_the_dispatcher_is_the_only_dynamic_import(package):
    assert dynamic_imports(package) == []


def test_no_command_imports_another():
    assert command_imports() == []


def test_the_walk_reaches_subpackages():
    """The command modules are two levels down: the walk must see them (and resolve
    their ``...`` imports to the packages they name)."""
    names = [_name(path, "gen") for path in _sources("gen")]
    assert "cli/cmd_match.py" in names and "flow/synthesise.py" in names
    modules = [module for module, _, _ in imported_modules(ROOT / "gen/cli/cmd_match.py")]
    assert ["golden", "data"] in modules and ["gen", "cli", "arguments"] in modules


def _tree(tmp_path, monkeypatch, files):
    """A source tree of ``files`` (path -> text) in ``tmp_path``, read in place of ours."""
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)


def test_a_backward_import_is_caught(tmp_path, monkeypatch):
    """Broken variant: an hdl module importing the golden model is reported."""
    _tree(tmp_path, monkeypatch, {"hdl/bad.py": "from ..golden.lr_check import INVALID\n"
                                                "def f():\n    from .core import NpStereoCore\n"})
    assert violations("hdl") == ["bad.py:1 imports golden",
                                 "bad.py:3 imports hdl inside a function"]


def test_a_backward_import_in_a_subpackage_is_caught(tmp_path, monkeypatch):
    """Broken variant: a module two levels down imports against the direction (``...``
    from ``golden/inner`` is the npstereo package) and inside a function."""
    _tree(tmp_path, monkeypatch, {"golden/inner/bad.py": (
        "from ...hdl.plan import MAX_BLOCK\nfrom ..data import read_image\n"
        "def f():\n    from . import other\n")})
    assert violations("golden") == ["inner/bad.py:1 imports hdl",
                                    "inner/bad.py:4 imports golden inside a function"]


def test_a_command_importing_a_command_is_caught(tmp_path, monkeypatch):
    """Broken variant: ``cmd_demo`` taking a helper from ``cmd_cosim``, in three spellings;
    a module that is not a command may import one."""
    _tree(tmp_path, monkeypatch, {
        "gen/cli/cmd_demo.py": "from .cmd_cosim import print_verdict\n"
                               "from . import arguments, cmd_match\n"
                               "from npstereo.gen.cli.cmd_eval import run_jobs\n",
        "gen/cli/main.py": "from .cmd_match import run\n"})
    assert command_imports() == ["cli/cmd_demo.py:1 imports gen.cli.cmd_cosim",
                                 "cli/cmd_demo.py:2 imports gen.cli.cmd_match",
                                 "cli/cmd_demo.py:3 imports gen.cli.cmd_eval"]


def test_a_dynamic_import_elsewhere_is_caught(tmp_path, monkeypatch):
    """Broken variant: a command importing a module by name; the dispatcher may."""
    _tree(tmp_path, monkeypatch, {
        "gen/cli/cmd_demo.py": "import importlib\n"
                               "def f():\n    importlib.import_module('npstereo.sim')\n"
                               "    __import__('npstereo.hdl')\n",
        "gen/cli/main.py": "import importlib\nimportlib.import_module('x')\n"})
    assert dynamic_imports("gen") == ["cli/cmd_demo.py:3 imports dynamically",
                                      "cli/cmd_demo.py:4 imports dynamically"]
