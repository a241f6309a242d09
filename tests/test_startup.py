"""What ``fogref render`` does before its first kernel, made cheaper without changing a result.

The times are measured by ``benchmarks/render_driver.py --startup`` (reports/benchmarks/
render_driver_startup.md); these tests check only that each shortcut gives what the long
way gives: the ``dr.syntax`` cache the same code objects, a quiet render no tqdm, the
CLI's exit-time ``gc.freeze`` only when ``main`` owns the process.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import pytest

from conftest import ROOT, SCENES

SOURCE = """
import drjit as dr


@dr.syntax
def count(n, step=1):
    i = 0
    while i < n:
        if i > 3:
            i += step
        i += 1
    return i
"""


def _load(path, name):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def syntax_calls(monkeypatch, tmp_path):
    """Dr.Jit's own ``syntax`` counted; the cache in ``tmp_path/cache``."""
    import drjit as dr

    original, calls = dr.syntax, []

    def counted(f=None, **kw):
        calls.append(getattr(f, "__qualname__", None))
        return original(f, **kw)

    monkeypatch.setattr(dr, "syntax", counted)
    monkeypatch.setenv("FOGREF_SYNTAX_CACHE", str(tmp_path / "cache"))
    return calls


def testcached_syntax_gives_dr_syntax_code_and_skips_it_on_a_hit(tmp_path, syntax_calls):
    import drjit as dr

    from fogref.render.variant import cached_syntax

    src = tmp_path / "looped.py"
    src.write_text(SOURCE)
    own = _load(src, "looped_own").count  # Dr.Jit's syntax, no cache
    assert syntax_calls == ["count"]
    counted = dr.syntax
    with cached_syntax():
        miss = _load(src, "looped_miss").count
    assert dr.syntax is counted  # restored
    assert syntax_calls == ["count", "count"] and len(list((tmp_path / "cache").iterdir())) == 1
    with cached_syntax():
        hit = _load(src, "looped_hit").count
    assert syntax_calls == ["count", "count"]  # from the cache, Dr.Jit not asked
    for f in (miss, hit):
        assert f.__code__ == own.__code__ and f.__defaults__ == own.__defaults__ == (1,)
        assert f.__qualname__ == own.__qualname__ and f.__code__.co_filename == str(src)
    assert "while_loop" in own.__code__.co_names  # it is the rewritten function


def test_an_edited_source_or_a_broken_entry_is_rewritten_not_reused(tmp_path, syntax_calls):
    from fogref.render.variant import cached_syntax

    src = tmp_path / "looped.py"
    src.write_text(SOURCE)
    with cached_syntax():
        first = _load(src, "looped_a").count
    src.write_text(SOURCE.replace("i += 1", "i += 2  # edited"))
    with cached_syntax():
        edited = _load(src, "looped_b").count
    assert syntax_calls == ["count", "count"] and edited.__code__ != first.__code__
    entries = sorted((tmp_path / "cache").iterdir())
    assert len(entries) == 2
    for e in entries:
        e.write_bytes(b"not marshal data")
    with cached_syntax():
        again = _load(src, "looped_c").count
    assert syntax_calls == ["count"] * 3 and again.__code__ == edited.__code__


def test_cache_off_or_unwritable_is_dr_syntax_itself(tmp_path, monkeypatch, syntax_calls):
    import drjit as dr

    from fogref.render.variant import cached_syntax

    src = tmp_path / "looped.py"
    src.write_text(SOURCE)
    monkeypatch.setenv("FOGREF_SYNTAX_CACHE", "off")
    counted = dr.syntax
    with cached_syntax():
        assert dr.syntax is counted
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv("FOGREF_SYNTAX_CACHE", str(blocker / "cache"))  # cannot be created
    with cached_syntax():
        f = _load(src, "looped_ro").count
    assert syntax_calls == ["count"] and f.__name__ == "count"


def test_set_variant_restores_dr_syntax(mitsuba):
    import drjit as dr
    import drjit.ast

    assert dr.syntax is drjit.ast.syntax


@pytest.mark.render
def test_quiet_render_does_not_import_tqdm(tmp_path, mitsuba, monkeypatch):
    from fogref.render.render import render

    monkeypatch.setitem(sys.modules, "tqdm", None)  # `import tqdm` now fails
    out = render(
        SCENES / "valley.xml",
        tmp_path / "q.exr",
        spp=1,
        overrides={"res": 8, "resy": 4},
        progress=False,
        png=False,
    )
    assert out.is_file()


def test_render_takes_dash_o():
    from fogref.cli import build_parser

    a = build_parser(only="render").parse_args(["render", "s.xml", "-o", "x.exr"])
    assert a.out == "x.exr"


def test_gc_frozen_only_when_main_owns_the_process():
    code = (
        "import gc, sys\nfrom fogref.cli import main\nsys.argv = ['fogref', '--version']\n"
        "try:\n    main({argv})\nexcept SystemExit:\n    pass\nprint(gc.get_freeze_count() > 0)\n"
    )
    for argv, frozen in (("", "True"), ("['--version']", "False")):
        r = subprocess.run(
            [sys.executable, "-c", code.format(argv=argv)], cwd=ROOT, capture_output=True, text=True
        )
        assert r.stdout.strip().splitlines()[-1] == frozen, r.stderr
