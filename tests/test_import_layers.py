"""The import layers: a lower layer never imports a higher one (checked on the source, with ``ast``).

Layers, low to high: ``fogref.media`` (physics) < ``fogref.models`` (shader ports)
< ``fogref.mapping`` (physical scene -> model, fits) < ``fogref.compare`` /
``fogref.study``; ``fogref.render`` and the Mitsuba plugins sit beside them.
Every ``import`` counts, at module level or inside a function.  Extend
:data:`FORBIDDEN` (layer -> forbidden imports) and :data:`ALLOWED` (module,
import) to add rules.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: package prefix -> imports its modules must not make (a name and its submodules).
FORBIDDEN = {
    "fogref.media": ("fogref.models", "fogref.mapping", "fogref.compare", "fogref.study", "fogref.render",
                     "fogref_plugins", "plugins", "mitsuba", "drjit"),
    "fogref.models": ("fogref.mapping", "fogref.compare", "fogref.study", "fogref.render",
                      "fogref_plugins", "plugins", "mitsuba", "drjit"),
    "fogref.mapping": ("fogref.compare", "fogref.study", "fogref.render", "fogref_plugins", "plugins",
                       "mitsuba", "drjit"),
}

#: (module, import) exceptions, each only inside a function (lazily): the Dr.Jit back end
#: of the closed forms, and its default Float (the variant's ``mitsuba.Float``).
ALLOWED = {
    ("fogref.media.ops", "drjit"): "lazy",
    ("fogref.media.ops", "mitsuba"): "lazy",
}


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[0] == "plugins":
        parts[0] = "fogref_plugins"
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports(path: Path):
    """``(imported module, line, at module level)`` for every import in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    mod = module_name(path)
    package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    top_level = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, node.lineno, id(node) in top_level
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = package.split(".")
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join(pkg + ([base] if base else []))
            yield base, node.lineno, id(node) in top_level
            for a in node.names:
                yield f"{base}.{a.name}", node.lineno, id(node) in top_level


def _under(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def sources():
    return sorted([*ROOT.glob("fogref/**/*.py"), *ROOT.glob("plugins/**/*.py")])


def violations():
    out = []
    for path in sources():
        mod = module_name(path)
        rules = [f for layer, fs in FORBIDDEN.items() if _under(mod, layer) for f in fs]
        for name, line, top in imports(path):
            for f in rules:
                if not _under(name, f):
                    continue
                allowed = ALLOWED.get((mod, f))
                if allowed == "lazy" and not top:
                    continue
                where = "module level" if top else "in a function"
                out.append(f"{path.relative_to(ROOT)}:{line}: {mod} imports {name} ({where})")
    return out


def test_the_rules_see_the_packages():
    names = {module_name(p) for p in sources()}
    for layer in FORBIDDEN:
        assert any(_under(n, layer) for n in names), f"no module under {layer}: the rule checks nothing"


def test_no_import_from_a_lower_layer_to_a_higher_one():
    bad = violations()
    assert not bad, "layer violations:\n" + "\n".join(bad)


@pytest.mark.parametrize("src, expected", [
    ("import drjit as dr\n", ["drjit"]),
    ("def f():\n    from fogref.study.fit import x\n", ["fogref.study.fit", "fogref.study.fit.x"]),
    ("from fogref import mapping\n", ["fogref", "fogref.mapping"]),
])
def test_the_parser_finds_imports(tmp_path, monkeypatch, src, expected):
    f = tmp_path / "fogref" / "media" / "probe.py"
    f.parent.mkdir(parents=True)
    f.write_text(src)
    monkeypatch.setitem(globals(), "ROOT", tmp_path)
    assert [name for name, _, _ in imports(f)] == expected
