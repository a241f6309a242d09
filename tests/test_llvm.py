"""LLVM discovery for Dr.Jit: newest >= 16 wins, 14/15 are never chosen, and a
machine without one gets a message that says what to install."""

import fogref.llvm as L


def test_prefers_newest_supported(monkeypatch, tmp_path):
    libs = {}
    for name in ("libLLVM-14.so.1", "libLLVM-15.so.1", "libLLVM.so.19.1", "libLLVM-17.so"):
        p = tmp_path / name
        p.write_bytes(b"")
        libs[name] = str(p)
    monkeypatch.setattr(L, "_SEARCH", [str(tmp_path / "libLLVM*")])
    assert L.find_llvm() == libs["libLLVM.so.19.1"]


def test_rejects_llvm_14_and_15(monkeypatch, tmp_path):
    for name in ("libLLVM-14.so.1", "libLLVM-15.so"):
        (tmp_path / name).write_bytes(b"")
    monkeypatch.setattr(L, "_SEARCH", [str(tmp_path / "libLLVM*")])
    assert L.find_llvm() is None


def test_environment_variable_wins(monkeypatch):
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", "/custom/libLLVM.so")
    assert L.ensure_llvm() == "/custom/libLLVM.so"


def test_clear_message_when_missing(monkeypatch, tmp_path):
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(L, "_SEARCH", [str(tmp_path / "none*")])
    assert L.ensure_llvm() is None
    assert "apt-get install libllvm19" in L.HELP and "DRJIT_LIBLLVM_PATH" in L.HELP


def test_require_llvm_raises_with_help(monkeypatch, tmp_path):
    from fogref.errors import FogrefError

    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(L, "_SEARCH", [str(tmp_path / "none*")])
    try:
        L.require_llvm()
    except FogrefError as e:
        assert "apt-get install libllvm19" in str(e)
    else:
        raise AssertionError("require_llvm() found an LLVM in an empty folder")


def test_import_does_not_touch_the_environment():
    """``import fogref`` finds no LLVM and imports neither Mitsuba nor Dr.Jit."""
    import os
    import subprocess
    import sys

    code = (
        "import os, sys, fogref, fogref.media, fogref.models; "
        "assert 'DRJIT_LIBLLVM_PATH' not in os.environ; "
        "assert 'mitsuba' not in sys.modules and 'drjit' not in sys.modules"
    )
    env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
