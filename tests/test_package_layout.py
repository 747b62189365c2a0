"""The layout rules of the Python package src/artibus/ (docs/developer/layout.md):

1. no import cycle: every ``import`` and ``from ... import`` of every module
   (function-level ones included, relative ones resolved; a literal
   ``importlib.import_module("artibus.x")`` or ``__import__("artibus.x")`` too),
   at module granularity: ``from artibus.x import y`` is an edge to the module
   ``artibus.x.y`` where that is a module, else to ``artibus.x``; a package is
   its ``__init__``;
2. no module above MAX_LINES lines; in the runner, the FMU and the bench sub-packages
   (LONG_FUNCTION_PARTS), no function above MAX_FUNCTION_LINES lines either (issue 37);
3. no private name (a leading underscore, not a dunder) imported from another
   sub-package (the first level below artibus: ``artibus.runner``,
   ``artibus.can``, ...; a module at the top, e.g. ``artibus.cli``, is a part of
   its own).

Each checker is first shown to fail on a small broken package made in tmp_path."""
import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "artibus"
MAX_LINES = 600
MAX_FUNCTION_LINES = 100
LONG_FUNCTION_PARTS = ("artibus.runner", "artibus.fmu", "artibus.bench")


# --- the checkers ---------------------------------------------------------------------

def modules(root):
    """{dotted module name: path} of the package in the folder ``root`` (a
    package's name is that of its __init__.py)."""
    out = {}
    for path in sorted(Path(root).rglob("*.py")):
        parts = list(path.relative_to(Path(root).parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _is_package(name, mods):
    return mods[name].name == "__init__.py"


def _target(name, mods):
    """The module an import of ``name`` loads last: ``name`` itself, else its
    longest prefix that is a module (``import artibus.x.nosuch``: artibus.x)."""
    parts = name.split(".")
    while parts:
        if ".".join(parts) in mods:
            return ".".join(parts)
        parts.pop()
    return None


def imports(name, mods):
    """[(line, imported module, [names taken from it])] of module ``name``,
    every import statement in it (module, class and function level)."""
    tree = ast.parse(mods[name].read_text(), filename=str(mods[name]))
    package = name if _is_package(name, mods) else name.rpartition(".")[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                t = _target(alias.name, mods)
                if t is not None:
                    out.append((node.lineno, t, []))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            for alias in node.names:
                full = f"{source}.{alias.name}"
                if full in mods:
                    out.append((node.lineno, full, []))
                else:
                    t = _target(source, mods)
                    if t is not None:
                        out.append((node.lineno, t, [alias.name]))
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)
              and (getattr(node.func, "id", None) == "__import__"
                   or getattr(node.func, "attr", None) == "import_module")):
            t = _target(node.args[0].value, mods)
            if t is not None:
                out.append((node.lineno, t, []))
    return out


def import_graph(root):
    """{module: {imported module: first line}} of the package in ``root``."""
    mods = modules(root)
    graph = {}
    for name in mods:
        edges = graph.setdefault(name, {})
        for line, target, _ in imports(name, mods):
            if target != name:
                edges.setdefault(target, line)
    return graph


def import_cycles(root):
    """Every import cycle, each as [a, b, ..., a] (one per strongly connected
    set of modules, found by depth-first search), with the lines: [(module, line)]."""
    graph = import_graph(root)
    cycles, state, stack = [], {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, {})):
            if state.get(m) == 1:
                loop = stack[stack.index(m):] + [m]
                cycles.append([(a, graph[a][b]) for a, b in zip(loop, loop[1:])])
            elif state.get(m) is None:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if state.get(n) is None:
            visit(n)
    return cycles


def long_modules(root, limit=MAX_LINES):
    """[(module, lines)] of the modules above ``limit`` lines."""
    out = []
    for name, path in modules(root).items():
        n = len(path.read_text().splitlines())
        if n > limit:
            out.append((name, n))
    return out


def long_functions(root, parts, limit=MAX_FUNCTION_LINES):
    """[(module, function, lines)] of the functions and methods (nested ones too) of the
    modules in ``parts`` (sub-packages) longer than ``limit`` lines, decorators and
    docstring included."""
    out = []
    for name, path in sorted(modules(root).items()):
        if not any(name == p or name.startswith(p + ".") for p in parts):
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                first = min([node.lineno] + [d.lineno for d in node.decorator_list])
                if node.end_lineno - first + 1 > limit:
                    out.append((name, node.name, node.end_lineno - first + 1))
    return out


def _part(name):
    """The sub-package a module belongs to: artibus.runner.core -> artibus.runner."""
    return ".".join(name.split(".")[:2])


def private_imports(root):
    """[(module, line, imported module, name)] of every private name a module
    imports from another sub-package."""
    mods = modules(root)
    out = []
    for name in mods:
        for line, source, names in imports(name, mods):
            taken = names or [source.rpartition(".")[2]]
            for n in taken:
                private = n.startswith("_") and not (n.startswith("__") and n.endswith("__"))
                if private and _part(source) != _part(name):
                    out.append((name, line, source, n))
    return out


def _write(root, files):
    for rel, text in files.items():
        p = Path(root) / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return Path(root) / next(iter(files)).split("/")[0]


# --- each checker fails on a broken package ---------------------------------------------

def test_cycle_found_in_a_broken_package(tmp_path):
    """a -> b at module level, b -> a inside a function through a relative
    import; c -> the package's __init__ -> c; d alone: two cycles, named."""
    pkg = _write(tmp_path, {
        "pkg/__init__.py": "def lazy():\n    from pkg.sub import c\n",
        "pkg/a.py": "from pkg.b import f\n",
        "pkg/b.py": "def f():\n    from . import a\n    return a\n",
        "pkg/sub/__init__.py": "",
        "pkg/sub/c.py": "import pkg\n",
        "pkg/d.py": "import os\nfrom pkg.sub import c\n",
    })
    cycles = import_cycles(pkg)
    named = sorted(" -> ".join(m for m, _ in c) + " -> " + c[0][0] for c in cycles)
    assert named == ["pkg -> pkg.sub.c -> pkg", "pkg.a -> pkg.b -> pkg.a"]
    assert dict(import_cycles(pkg)[1])["pkg.b"] == 2          # the line of the function-level import
    # without the two back edges: none
    (pkg / "b.py").write_text("def f():\n    return 1\n")
    (pkg / "sub" / "c.py").write_text("import os\n")
    assert import_cycles(pkg) == []


def test_dynamic_import_counts_as_an_edge(tmp_path):
    pkg = _write(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "import importlib\ndef f():\n    return importlib.import_module('pkg.b')\n",
        "pkg/b.py": "from pkg import a\n",
    })
    assert [[m for m, _ in c] for c in import_cycles(pkg)] == [["pkg.a", "pkg.b"]]


def test_long_module_found_in_a_broken_package(tmp_path):
    pkg = _write(tmp_path, {"pkg/__init__.py": "", "pkg/short.py": "x = 1\n" * MAX_LINES,
                            "pkg/long.py": "x = 1\n" * (MAX_LINES + 1)})
    assert long_modules(pkg) == [("pkg.long", MAX_LINES + 1)]


def test_long_function_found_in_a_broken_package(tmp_path):
    """A function, a method and a nested function over the limit are found, in the parts
    named only; one of exactly the limit is not."""
    body = "    x = 1\n"
    pkg = _write(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/one/__init__.py": "",
        "pkg/one/m.py": ("def ok():\n" + body * (MAX_FUNCTION_LINES - 1)
                         + "def long():\n" + body * MAX_FUNCTION_LINES
                         + "class C:\n    @staticmethod\n    def method():\n" + ("    " + body) * (MAX_FUNCTION_LINES - 1)
                         + "def outer():\n    def inner():\n" + ("    " + body) * (MAX_FUNCTION_LINES + 1)),
        "pkg/two/__init__.py": "",
        "pkg/two/n.py": "def long():\n" + body * (MAX_FUNCTION_LINES + 5),
    })
    found = sorted(long_functions(pkg, ("pkg.one",)))
    assert found == [("pkg.one.m", "inner", MAX_FUNCTION_LINES + 2), ("pkg.one.m", "long", MAX_FUNCTION_LINES + 1),
                     ("pkg.one.m", "method", MAX_FUNCTION_LINES + 1), ("pkg.one.m", "outer", MAX_FUNCTION_LINES + 3)]


def test_private_import_found_in_a_broken_package(tmp_path):
    """A private name from another sub-package is found (by name, by a module's
    name, relative or absolute); from its own sub-package, or a dunder, it is not."""
    pkg = _write(tmp_path, {
        "pkg/__init__.py": "from pkg.one.m import __doc__\n",
        "pkg/one/__init__.py": "",
        "pkg/one/m.py": "from pkg.two.n import _secret, public\n_y = 1\n",
        "pkg/one/k.py": "from pkg.one.m import _y\nfrom .m import _y as y\n",
        "pkg/one/_hidden.py": "",
        "pkg/two/__init__.py": "",
        "pkg/two/n.py": "_secret = public = 1\ndef f():\n    from ..one import _hidden\n    from pkg.one.m import _y\n",
        "pkg/top.py": "from pkg.two import n\nfrom pkg.two.n import _secret\n",
    })
    found = sorted((m, line, n) for m, line, _, n in private_imports(pkg))
    assert found == [("pkg.one.m", 1, "_secret"), ("pkg.top", 2, "_secret"),
                     ("pkg.two.n", 3, "_hidden"), ("pkg.two.n", 4, "_y")]


# --- the package keeps the rules ------------------------------------------------------------

def test_the_package_has_no_import_cycle():
    cycles = import_cycles(PACKAGE)
    assert not cycles, "import cycles in src/artibus:\n" + "\n".join(
        "  " + " -> ".join(f"{m} (line {line})" for m, line in c) + f" -> {c[0][0]}" for c in cycles)


def test_no_module_above_the_limit():
    assert not long_modules(PACKAGE), f"modules above {MAX_LINES} lines: " + ", ".join(
        f"{m} ({n})" for m, n in long_modules(PACKAGE))


def test_no_long_function_in_the_runner_fmu_and_bench():
    bad = long_functions(PACKAGE, LONG_FUNCTION_PARTS)
    assert not bad, f"functions above {MAX_FUNCTION_LINES} lines: " + ", ".join(
        f"{m}.{f} ({n})" for m, f, n in bad)


def test_no_private_name_imported_from_another_sub_package():
    bad = private_imports(PACKAGE)
    assert not bad, "private names imported across sub-packages:\n" + "\n".join(
        f"  {m}:{line}: {n} from {src}" for m, line, src, n in bad)


def test_the_public_api_at_the_top():
    """The README's Python example: artibus.run, artibus.Simulation, artibus.sweep(...)
    from the package itself; the runner's names where they always were."""
    import artibus
    from artibus.runner import Simulation, can_signal, core_library_path, read_units, run, save, units_path
    assert artibus.run is run and artibus.Simulation is Simulation
    assert callable(artibus.sweep) and callable(artibus.sweep.release) and callable(artibus.sweep.study)
    assert {"__version__", "ROOT", "ArtibusError", "fmu_dir", "fmu_path"} <= set(dir(artibus))
    with pytest.raises(AttributeError):
        artibus.nosuch
