"""The import graph of fogref: floors, no cycles, no work on import.

fogref is built in floors; each floor imports only the floors below it (see
``docs/design.md``, "Architecture"). The graph is read from the source with
:mod:`ast`: every ``import`` and ``from ... import`` counts, at module level and
inside functions alike (a function-level import is still an arrow between
modules, it only runs later). ``plugins/`` is the package ``fogref_plugins``.
Imports sit at the top of their module: every function-level import and every private
name imported from another module is listed below with its reason.
"""

from __future__ import annotations

import ast
import functools
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"fogref": ROOT / "fogref", "fogref_plugins": ROOT / "plugins"}

#: Floors, low to high: (name, module prefixes). A module belongs to the floor of
#: its longest matching prefix; "fogref" alone is the package facade (``fogref.set_variant``).
FLOORS: list[tuple[str, tuple[str, ...]]] = [
    # leaf utilities that import no other fogref module; every floor may use them
    (
        "base",
        (
            "fogref._version",
            "fogref.errors",
            "fogref.params",
            "fogref.atomic",
            "fogref.llvm",
            "fogref.cluster",
            "fogref.cache_dir",
            "fogref.cores",
            "fogref.shipped_scenes",
        ),
    ),
    ("media", ("fogref.media",)),  # physics: numpy, Dr.Jit only lazily
    # the ground-truth schema, its I/O and the one display transform
    ("gbuffer", ("fogref.gbuffer", "fogref.exrio", "fogref.display")),
    ("models", ("fogref.models",)),  # ports of the engines' shaders
    # the scene XML read once: parse, $defaults, vocabulary and ranges, inputs, describe, writer, editor
    ("scene", ("fogref.scene",)),
    ("mapping", ("fogref.mapping",)),  # physical scene -> model parameters, fits
    # the Mitsuba plugins: the heightfog medium, the fogpath integrator and its passes
    ("plugins", ("fogref_plugins",)),
    ("render", ("fogref.render",)),  # Mitsuba glue: variant, scenes, the render driver and cache
    ("compare", ("fogref.compare",)),
    ("engines", ("fogref.engines",)),  # real engines in headless Chromium (selenium), lazily
    ("study", ("fogref.study",)),
    ("html", ("fogref.html",)),  # self-contained HTML reports (fogref.html)
    # entry points: the command line, the pytest plugin and the facade (fogref.set_variant)
    ("cli", ("fogref.cli", "fogref.pytest_plugin", "fogref.info", "fogref")),
]
#: floors that must not import Mitsuba or Dr.Jit at module level: all but the plugins and render
NO_MITSUBA_AT_IMPORT = {name for name, _ in FLOORS} - {"plugins", "render"}


def _modules() -> dict[str, tuple[Path, bool]]:
    """Module name -> (file, is_package) for every .py file of fogref and fogref_plugins."""
    out = {}
    for pkg, base in PACKAGES.items():
        for p in sorted(base.rglob("*.py")):
            parts = [pkg, *p.relative_to(base).with_suffix("").parts]
            is_pkg = parts[-1] == "__init__"
            out[".".join(parts[:-1] if is_pkg else parts)] = (p, is_pkg)
    return out


MODULES = _modules()


def floor_of(module: str) -> int:
    """Index in FLOORS of ``module``'s floor (longest prefix wins)."""
    best, best_len = None, -1
    for i, (_, prefixes) in enumerate(FLOORS):
        for pre in prefixes:
            exact_only = pre == "fogref"
            hit = module == pre or (not exact_only and module.startswith(pre + "."))
            if hit and len(pre) > best_len:
                best, best_len = i, len(pre)
    if best is None:
        raise AssertionError(f"{module}: on no floor; add it to FLOORS in {Path(__file__).name}")
    return best


@functools.cache
def _parsed(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), str(path))


def _function_nodes(tree):
    inside = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            for sub in ast.walk(node):
                if sub is not node:
                    inside.add(id(sub))
    return inside


def imports_of(module: str):
    """(imported name, line, at module level) for every import statement in ``module``.

    ``from a.b import c`` names ``a.b.c`` when that is a module, else ``a.b``;
    relative imports are resolved against the package.
    """
    path, is_pkg = MODULES[module]
    tree = _parsed(path)
    in_function = _function_nodes(tree)
    package = module if is_pkg else module.rpartition(".")[0]
    for node in ast.walk(tree):
        top = id(node) not in in_function
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, top
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package
                for _ in range(node.level - 1):
                    base = base.rpartition(".")[0]
                src = f"{base}.{node.module}" if node.module else base
            else:
                src = node.module
            for alias in node.names:
                sub = f"{src}.{alias.name}"
                yield (sub if sub in MODULES else src), node.lineno, top


#: What the package facade ``fogref/__init__.py`` offers, and the module behind each name.
#: ``import fogref`` alone is no arrow (every submodule import runs the facade anyway, and
#: its module level imports only base modules, see test_the_package_facade_imports_lazily);
#: each ``fogref.<name>`` or ``from fogref import <name>`` is an arrow to the module behind it.
FACADE = {
    "set_variant": "fogref.render.variant",
    "ensure_llvm": "fogref.llvm",
    "__version__": "fogref._version",
    "__file__": "fogref._version",
    "__name__": "fogref._version",
    "__path__": "fogref._version",
}


def _resolve(name: str) -> str | None:
    if name.startswith("fogref.") and name.split(".")[1] in FACADE:
        return FACADE[name.split(".")[1]]
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _facade_uses(module: str):
    """(``fogref.<name>``, line) for each attribute use of a bare ``import fogref``."""
    path, _ = MODULES[module]
    tree = _parsed(path)
    aliases = {
        a.asname or a.name
        for n in ast.walk(tree)
        if isinstance(n, ast.Import)
        for a in n.names
        if a.name == "fogref"
    }
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases:
            yield f"fogref.{node.attr}", node.lineno


@functools.cache
def import_graph() -> dict[str, dict[str, int]]:
    """module -> {imported fogref module: line} (self-imports dropped; read once, not changed)."""
    graph: dict[str, dict[str, int]] = {m: {} for m in MODULES}
    for m in MODULES:
        uses = [(n, line) for n, line, _ in imports_of(m) if n != "fogref"] + list(_facade_uses(m))
        for name, line in uses:
            if name.split(".")[0] not in PACKAGES:
                continue
            target = _resolve(name)
            if target and target != m:
                graph[m].setdefault(target, line)
    return graph


def _cycles(graph) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _where(module: str, line: int) -> str:
    return f"{MODULES[module][0].relative_to(ROOT)}:{line}"


def test_every_module_has_a_floor():
    for m in MODULES:
        floor_of(m)


def test_the_checks_see_what_they_look_for():
    assert _cycles({"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}, "d": {"a": 1}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b": 1}, "b": {}}) == []
    assert FLOORS[floor_of("fogref.models.ue4")][0] == "models"
    assert FLOORS[floor_of("fogref_plugins.fogpath")][0] == "plugins"
    assert FLOORS[floor_of("fogref.render.render")][0] == "render"
    assert FLOORS[floor_of("fogref")][0] == "cli" and FLOORS[floor_of("fogref.errors")][0] == "base"
    assert "fogref.media" in import_graph()["fogref.models.ue4"]
    assert _resolve("fogref.set_variant") == "fogref.render.variant" and _resolve("fogref") == "fogref"


def test_no_import_cycle():
    graph = import_graph()
    cycles = _cycles(graph)
    msg = []
    for comp in cycles:
        arrows = [f"{a} -> {b} ({_where(a, graph[a][b])})" for a in comp for b in graph[a] if b in comp]
        msg.append("cycle among " + ", ".join(comp) + ":\n    " + "\n    ".join(arrows))
    assert not cycles, "\n".join(msg)


def test_each_floor_imports_only_floors_below():
    graph = import_graph()
    bad = []
    for a, targets in graph.items():
        fa = floor_of(a)
        for b, line in targets.items():
            fb = floor_of(b)
            if fb > fa:
                bad.append(f"{_where(a, line)}: {a} ({FLOORS[fa][0]}) imports {b} ({FLOORS[fb][0]})")
    assert not bad, "imports from a lower floor to a higher one:\n" + "\n".join(sorted(bad))


def test_base_modules_import_only_base():
    graph = import_graph()
    base = [m for m in MODULES if floor_of(m) == 0]
    bad = [
        f"{_where(m, line)}: {m} imports {t}"
        for m in base
        for t, line in graph[m].items()
        if floor_of(t) != 0
    ]
    assert not bad, "\n".join(bad)


def test_no_mitsuba_or_drjit_at_module_level_below_render():
    bad = []
    for m in MODULES:
        if FLOORS[floor_of(m)][0] not in NO_MITSUBA_AT_IMPORT:
            continue
        for name, line, top in imports_of(m):
            if top and name.split(".")[0] in ("mitsuba", "drjit", "fogref_plugins"):
                bad.append(f"{_where(m, line)}: {m} imports {name} at module level")
    assert not bad, "\n".join(bad)


def test_the_scene_floor_never_imports_mitsuba():
    """``fogref.scene`` reads and writes scene XML without Mitsuba or Dr.Jit, inside functions too."""
    bad = [
        f"{_where(m, line)}: {m} imports {name}"
        for m in MODULES
        if FLOORS[floor_of(m)][0] == "scene"
        for name, line, _ in imports_of(m)
        if name.split(".")[0] in ("mitsuba", "drjit", "fogref_plugins")
    ]
    assert not bad, "\n".join(bad)


def test_the_package_facade_imports_lazily():
    """``fogref/__init__.py`` imports only base modules at module level; set-up is a call."""
    bad = [
        f"{_where('fogref', line)}: {name}"
        for name, line, top in imports_of("fogref")
        if top and name.startswith("fogref") and floor_of(_resolve(name)) != 0
    ]
    import fogref

    # "@py_builtins"/"@pytest_ar": pytest rewrites the asserts of a pytest11 plugin's package (fogref)
    offered = {n for n in vars(fogref) if not n.startswith(("_", "@")) and f"fogref.{n}" not in MODULES}
    assert offered - {"annotations"} <= set(FACADE), "add the facade's new names to FACADE"
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    "modules", ["fogref", "fogref.media, fogref.models", "fogref.mapping", "fogref.gbuffer, fogref.exrio"]
)
def test_import_does_no_mitsuba_work(modules):
    """Importing the physics, models, mapping and schema imports neither Mitsuba nor Dr.Jit
    and leaves ``DRJIT_LIBLLVM_PATH`` alone (checked in a fresh interpreter)."""
    if modules == "fogref.mapping" and "fogref.mapping" not in MODULES:
        pytest.skip("fogref.mapping not there yet")
    code = (
        f"import os, sys, {modules}; "
        "bad = [m for m in ('mitsuba', 'drjit', 'fogref_plugins') if m in sys.modules]; "
        "assert not bad, bad; assert 'DRJIT_LIBLLVM_PATH' not in os.environ"
    )
    env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    r = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]


# ---------------------------------------------------------------------------------------------
# Imports sit at the top of their module (CONTRIBUTING.md, "Imports"); these are the exceptions.

#: (a) importing it does work: Mitsuba, Dr.Jit (the floors below ``render`` and ``import fogref``
#: must not load them), or a library that reads the environment as it loads
DOES_WORK = "importing it does work"
#: (b) an optional dependency, absent from a plain install
OPTIONAL = "optional dependency"
#: (c) a heavy library the module's common path does not need, its start-up cost measured
#: (CPU seconds of ``python -c "import X"`` over a bare interpreter, on the 2-core machine)
HEAVY = "heavy library, measured"
#: (d) the floors forbid it at the top
FLOOR = "the floors forbid it"

#: Every function-level import of fogref/ and plugins/: module -> {imported name: reason}. The
#: imported name is what ``import a.b`` or ``from a import b`` (``a.b``) names.
LAZY_IMPORTS: dict[str, dict[str, str]] = {
    # the renderer (numpy, the plugins, the scene readers: 0.2 s over the command's module):
    # `fogref render --help` and its option errors answer without it (tests/test_cli_spec.py)
    "fogref.cli.render": {"fogref.render.render.render": HEAVY},
    # dask.distributed 0.8 s: a render or sweep in one process never starts a cluster
    "fogref.cluster": {
        "dask.config": HEAVY,
        "dask.distributed.Client": HEAVY,
        "dask.distributed.LocalCluster": HEAVY,
    },
    # scipy.special 0.3 s (scipy.stats 1.0-1.4 s): `fogref compare --help` and the pytest plugin
    # import the checker
    "fogref.compare.check": {"pytest": OPTIONAL, "scipy.special.ndtri": HEAVY},
    "fogref.compare.intervals": {"scipy.special.stdtrit": HEAVY},
    # flip_evaluator"s libgomp reads OMP_WAIT_POLICY as it loads; it is set just before
    "fogref.compare.perceptual": {"flip_evaluator": DOES_WORK},
    # matplotlib 0.4 s (pyplot 0.9 s): only when figures are written
    "fogref.compare.plots": {
        "matplotlib": HEAVY,
        "matplotlib.backends.backend_agg.FigureCanvasAgg": HEAVY,
        "matplotlib.figure.Figure": HEAVY,
    },
    # selenium, Chromium's driver: the `test` extra only
    "fogref.engines.browser": {
        "selenium": OPTIONAL,
        "selenium.common.exceptions.JavascriptException": OPTIONAL,
        "selenium.common.exceptions.TimeoutException": OPTIONAL,
        "selenium.common.exceptions.WebDriverException": OPTIONAL,
        "selenium.webdriver": OPTIONAL,
        "selenium.webdriver.chrome.service.Service": OPTIONAL,
        "selenium.webdriver.support.ui.WebDriverWait": OPTIONAL,
    },
    "fogref.engines.view": {"mitsuba": DOES_WORK},
    "fogref.gbuffer": {"drjit": DOES_WORK},
    # pandas 0.7 s: only for a DataFrame"s display
    "fogref.html.notebook": {"pandas": HEAVY},
    # scipy.optimize 0.7 s: `import fogref.mapping` (which imports every mapping module) and
    # the mappings that need no fit go without it
    "fogref.mapping.fit": {"scipy.optimize.least_squares": HEAVY},
    "fogref.mapping.lobe": {"scipy.optimize.minimize_scalar": HEAVY, "scipy.optimize.nnls": HEAVY},
    "fogref.mapping.unreal_basis": {"scipy.optimize.minimize_scalar": HEAVY, "scipy.optimize.nnls": HEAVY},
    # scipy.special 0.5 s: only droplet fogs; miepython (0.5 s) reads MIEPYTHON_USE_JIT as it loads
    "fogref.media.mie": {"miepython": DOES_WORK, "scipy.special.gammaincinv": HEAVY},
    # the media floor runs without Mitsuba; Dr.Jit only for the plugins' back end and the sky
    "fogref.media.ops": {"drjit": DOES_WORK, "mitsuba": DOES_WORK},
    # scipy.integrate 0.8 s: only the horizon share of a lobe (hg_upper_fraction)
    "fogref.media.single_scatter": {"scipy.integrate": HEAVY},
    "fogref.media.sky": {"drjit": DOES_WORK, "mitsuba": DOES_WORK},
    # pytest loads this plugin in every session of a project that installs fogref; the render
    # cache (0.5 s) only for a test that asks for a truth
    "fogref.pytest_plugin": {
        "fogref.render.cache.cached_truth": HEAVY,
        "fogref.render.cache.default_cache_dir": HEAVY,
    },
    # dask.distributed 0.8 s: a render in one process never submits a pass
    "fogref.render.distributed": {"dask.distributed.as_completed": HEAVY},
    "fogref.render.load": {"drjit": DOES_WORK, "mitsuba": DOES_WORK},
    # tqdm 0.03 s (`python -X importtime`): a quiet render shows no bar (tests/test_startup.py)
    "fogref.render.render": {"drjit": DOES_WORK, "mitsuba": DOES_WORK, "tqdm.tqdm": HEAVY},
    "fogref.render.sunsky": {"mitsuba": DOES_WORK},
    "fogref.render.variant": {"drjit": DOES_WORK, "mitsuba": DOES_WORK},
    # colour 0.8-1.4 s (it imports its plotting package): only the spectral study
    "fogref.study.spectral_rgb": {"colour": HEAVY},
    # scipy.stats.qmc 1.4 s: only the random and lhs designs
    "fogref.study.sweep.design": {"scipy.stats.qmc": HEAVY},
    # `fogref sweep --help` and load_sweep import the package; Dask only when a sweep runs
    "fogref.study.sweep.run": {"dask.distributed.as_completed": HEAVY},
    # matplotlib 0.4 s, pandas 0.7 s: only when the table and its figures are written
    "fogref.study.sweep.table": {"matplotlib.ticker.LogFormatter": HEAVY, "pandas": HEAVY},
    "fogref.study.sweep.task": {
        "distributed.Lock": HEAVY,
        "distributed.get_worker": HEAVY,
        "drjit": DOES_WORK,
        "mitsuba": DOES_WORK,
    },
    # the plugins' modules import Mitsuba, which needs a variant set first
    "fogref_plugins": {
        "fogref_plugins.fog_medium.register": DOES_WORK,
        "fogref_plugins.fogpath.register": DOES_WORK,
        "fogref_plugins.tab_phase.register": DOES_WORK,
    },
}

#: Every import of a private name (``from fogref.x import _name``) from another module:
#: module -> {imported name: reason}. ``benchmarks.*`` are the scripts of benchmarks/.
PRIVATE_IMPORTS: dict[str, dict[str, str]] = {}


def _import_nodes(tree, module: str, is_pkg: bool):
    """(node, imported names, inside a function) for each import statement of ``tree``; ``from a
    import b`` names ``a.b``, relative imports resolved against ``module``'s package."""
    in_function = _function_nodes(tree)
    package = module if is_pkg else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = package
                for _ in range(node.level - 1):
                    pkg = pkg.rpartition(".")[0]
                base = f"{pkg}.{node.module}" if node.module else pkg
            names = [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        yield node, names, id(node) in in_function


def function_imports(tree: ast.Module, module: str = "m", is_pkg: bool = False) -> set[tuple[str, int]]:
    """(imported name, line) of every import inside a function or lambda of ``tree``.

    >>> sorted(function_imports(ast.parse("import os\\ndef f():\\n    from fogref import params as P\\n")))
    [('fogref.params', 3)]
    """
    nodes = _import_nodes(tree, module, is_pkg)
    return {(n, node.lineno) for node, names, inside in nodes if inside for n in names}


def private_imports(tree: ast.Module, module: str = "m", is_pkg: bool = False) -> set[tuple[str, int]]:
    """(imported name, line) of every private name (``_x``, not a module, not a dunder) that
    ``tree`` imports from a module of fogref or fogref_plugins."""
    out = set()
    for node, names, _ in _import_nodes(tree, module, is_pkg):
        if not isinstance(node, ast.ImportFrom):
            continue
        for name in names:
            src, _, last = name.rpartition(".")
            if (
                src.split(".")[0] in PACKAGES
                and last.startswith("_")
                and not last.startswith("__")
                and name not in MODULES
            ):
                out.add((name, node.lineno))
    return out


def _sources():
    """(module name, file, is_package) for fogref, fogref_plugins and the benchmarks' scripts."""
    for m, (path, is_pkg) in MODULES.items():
        yield m, path, is_pkg
    for path in sorted((ROOT / "benchmarks").glob("*.py")):
        yield f"benchmarks.{path.stem}", path, False


def _unlisted_and_stale(found: dict[str, set[tuple[str, int]]], allowed: dict[str, dict[str, str]]):
    unlisted = [
        f"{path}:{line}: {m} imports {name}"
        for m, (path, hits) in found.items()
        for name, line in sorted(hits)
        if name not in allowed.get(m, {})
    ]
    seen = {(m, name) for m, (_, hits) in found.items() for name, _ in hits}
    stale = [f"{m}: {name}" for m, names in allowed.items() for name in names if (m, name) not in seen]
    return unlisted, stale


def test_the_import_checks_see_what_they_look_for():
    src = (
        "from fogref.errors import FogrefError\n"
        "from fogref.study.sweep.values import _err, as_str\n"
        "def f():\n"
        "    import matplotlib.pyplot as plt\n"
        "    g = lambda: __import__('x')\n"
        "    from .sections import _read\n"
    )
    tree = ast.parse(src)
    assert function_imports(tree, "fogref.study.sweep.spec") == {
        ("matplotlib.pyplot", 4),
        ("fogref.study.sweep.sections._read", 6),
    }
    assert private_imports(tree, "fogref.study.sweep.spec") == {
        ("fogref.study.sweep.values._err", 2),
        ("fogref.study.sweep.sections._read", 6),
    }
    assert private_imports(ast.parse("from fogref import _version\nfrom os import _exit\n")) == set()
    unlisted, stale = _unlisted_and_stale({"m": ("m.py", {("a", 3)})}, {"m": {"b": HEAVY}})
    assert unlisted == ["m.py:3: m imports a"] and stale == ["m: b"]


def test_imports_are_at_the_top_unless_listed():
    """A function-level import is in LAZY_IMPORTS with its reason; a listed one still exists."""
    found = {}
    for m, path, is_pkg in _sources():
        if m.split(".")[0] in PACKAGES:
            hits = function_imports(_parsed(path), m, is_pkg)
            found[m] = (path.relative_to(ROOT), hits)
    unlisted, stale = _unlisted_and_stale(found, LAZY_IMPORTS)
    assert not unlisted, (
        "imports inside functions; move them to the top of the module, or list them in LAZY_IMPORTS "
        "with the reason (CONTRIBUTING.md, 'Imports'):\n" + "\n".join(unlisted)
    )
    assert not stale, "LAZY_IMPORTS lists imports that are gone; remove them:\n" + "\n".join(stale)
    assert set(LAZY_IMPORTS) <= set(MODULES)
    reasons = {DOES_WORK, OPTIONAL, HEAVY, FLOOR}
    assert {r for names in LAZY_IMPORTS.values() for r in names.values()} <= reasons


def test_no_private_name_is_imported_from_another_module():
    """``from fogref.x import _name`` in fogref/, plugins/ or benchmarks/ is in PRIVATE_IMPORTS;
    a name used across modules is public (or the code moves to where it is used)."""
    found = {}
    for m, path, is_pkg in _sources():
        found[m] = (path.relative_to(ROOT), private_imports(_parsed(path), m, is_pkg))
    unlisted, stale = _unlisted_and_stale(found, PRIVATE_IMPORTS)
    assert not unlisted, "private names imported from another module:\n" + "\n".join(unlisted)
    assert not stale, "PRIVATE_IMPORTS lists imports that are gone; remove them:\n" + "\n".join(stale)
