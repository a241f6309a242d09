"""Mitsuba set-up on an explicit call: LLVM, the variant, fogref's plugins.

:func:`set_variant` is the one place where fogref imports Mitsuba for the
renderer's sake; ``import fogref`` does not call it (see :mod:`fogref`).

Start-up (``benchmarks/render_driver.py --startup``): importing Mitsuba, setting a
variant and registering fogpath run ``@dr.syntax`` on 11 functions (Mitsuba's
Python integrators and projective helpers, fogpath's ``sample``), each a parse, an
AST rewrite and a compile of its source, in every process's start (twice for
Mitsuba's integrators while fogpath's ``import mitsuba.ad...`` loads them a second time).
While :func:`set_variant` runs, ``dr.syntax`` is wrapped by :func:`cached_syntax`,
which keeps the rewritten code objects on disk, keyed on the source file's bytes.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import marshal
import os
import types
from pathlib import Path

import fogref_plugins

from fogref import params
from fogref.atomic import atomic_write
from fogref.errors import FogrefError
from fogref.llvm import DEFAULT_VARIANT, HELP, ensure_llvm

#: The Mitsuba variants fogref renders with: its plugins (fogpath, heightfog) need an RGB
#: autodiff variant, on the CPU (LLVM) or an NVIDIA GPU (CUDA).
VARIANTS = ("llvm_ad_rgb", "cuda_ad_rgb")
#: What a CUDA variant on a machine without CUDA says (one line, not Dr.Jit's internals).
NO_CUDA = "{name} needs an NVIDIA GPU with CUDA; none found here: use llvm_ad_rgb"
_registered: set[str] = set()


def syntax_cache_dir():
    """The folder of :func:`cached_syntax`'s code objects (``$FOGREF_SYNTAX_CACHE``, see
    :func:`_cache_dir_from`), or None when it is off."""
    return _cache_dir_from(os.environ.get("FOGREF_SYNTAX_CACHE"))


def _cache_dir_from(setting):
    """The syntax cache's folder for a ``$FOGREF_SYNTAX_CACHE`` value: unset, the default
    ``~/.cache/fogref/drjit-syntax``; ``0``, ``off`` or empty, None (no cache); else that folder.

    >>> _cache_dir_from(None).parts[-3:], _cache_dir_from("off"), str(_cache_dir_from("/tmp/s"))
    (('.cache', 'fogref', 'drjit-syntax'), None, '/tmp/s')
    """
    if setting is None:
        return Path.home() / ".cache" / "fogref" / "drjit-syntax"
    return None if setting.strip().lower() in ("", "0", "off", "false", "no") else Path(setting)


@contextlib.contextmanager
def cached_syntax():
    """Within the block, ``drjit.syntax`` keeps its rewritten code objects on disk.

    ``@dr.syntax`` turns a function's source into another function (Dr.Jit's
    ``while``/``if`` rewrite) when the decorated module is imported: a parse, an
    AST rewrite and a compile per function, in every process.  Here a
    cache hit returns the same function built the same way from the stored code
    object (``marshal``, as Python's ``__pycache__``); a miss, or any failure to
    read or write the cache, calls Dr.Jit's own ``syntax`` (and stores its result).
    The key holds everything the rewrite depends on: the bytes of the source file,
    its path, the function's qualified name and first line, the ``recursive`` flag,
    Dr.Jit's version and Python's bytecode magic number, so an edited file or an
    upgraded Dr.Jit or Python never gets stale code.  Calls with ``print_ast``/``print_code``
    are passed through.  ``drjit.syntax`` is restored when the block ends.
    """
    folder = syntax_cache_dir()
    if folder is None:
        yield
        return
    import drjit as dr

    original = dr.syntax
    digests: dict[str, str] = {}

    def file_digest(filename: str) -> str:
        if filename not in digests:
            with open(filename, "rb") as fh:
                digests[filename] = hashlib.sha256(fh.read()).hexdigest()
        return digests[filename]

    def syntax(f=None, *, recursive=False, print_ast=False, print_code=False):
        if f is None:
            return lambda g: syntax(g, recursive=recursive, print_ast=print_ast, print_code=print_code)
        if (
            print_ast
            or print_code
            or not isinstance(f, types.FunctionType)
            or f.__module__.startswith(("drjit", "pytest"))
        ):  # Dr.Jit's own output or error
            return original(f, recursive=recursive, print_ast=print_ast, print_code=print_code)
        code = f.__code__
        try:
            key = repr(
                (
                    dr.__version__,
                    importlib.util.MAGIC_NUMBER.hex(),
                    f.__qualname__,
                    code.co_filename,
                    code.co_firstlineno,
                    bool(recursive),
                    file_digest(code.co_filename),
                )
            )
        except OSError:  # no source file: Dr.Jit's own error or result
            return original(f, recursive=recursive)
        path = folder / (hashlib.sha256(key.encode()).hexdigest()[:32] + ".code")
        try:
            new_code = marshal.loads(path.read_bytes())
            if not isinstance(new_code, types.CodeType) or new_code.co_name != f.__name__:
                raise ValueError("not the code object of this function")
        except (OSError, ValueError, EOFError, TypeError):
            new = original(f, recursive=recursive)
            with contextlib.suppress(OSError, ValueError):
                atomic_write(path, lambda tmp: Path(tmp).write_bytes(marshal.dumps(new.__code__)))
            return new
        new = types.FunctionType(new_code, f.__globals__)  # as drjit.ast.syntax builds it
        new.__defaults__ = f.__defaults__
        return new

    dr.syntax = syntax
    try:
        yield
    finally:
        dr.syntax = original


def _has_cuda() -> bool:
    """Whether Dr.Jit finds a CUDA device (a driver and a GPU)."""
    import drjit as dr

    try:
        return bool(dr.has_backend(dr.JitBackend.CUDA))
    except Exception:  # a broken driver install: no usable CUDA
        return False


def set_variant(name: str | None = None) -> str:
    """Set the Mitsuba variant and register fogref's plugins for it.

    Parameters
    ----------
    name
        A Mitsuba variant such as ``"llvm_ad_rgb"`` (default) or
        ``"cuda_ad_rgb"``. None keeps the variant already set, else uses
        ``$FOGREF_VARIANT``, else ``"llvm_ad_rgb"``.

    Returns
    -------
    str
        The variant now set.

    Raises
    ------
    fogref.errors.ParameterError
        The variant is not one of :data:`VARIANTS` (``scalar_rgb``, spectral variants:
        fogref's plugins need an RGB autodiff variant), with the allowed list.
    fogref.errors.FogrefError
        The variant is not one of ``mitsuba.variants()``, it fails to start, it is
        ``cuda_*`` and Dr.Jit finds no CUDA device (:data:`NO_CUDA`), or it is an
        ``llvm_*`` variant and no LLVM >= 16 was found.

    Notes
    -----
    ``$DRJIT_LIBLLVM_PATH`` is set (:func:`fogref._llvm.ensure_llvm`) before
    Mitsuba is imported, so Dr.Jit's LLVM back end starts with a supported
    LLVM. The plugins (``fogref_plugins.register``: the ``heightfog`` medium
    and the ``fogpath`` integrator) are registered once per variant; Mitsuba
    keeps plugin registrations per variant.
    """
    if name is not None:
        params.choice(name, "variant", VARIANTS, "fogref.set_variant")
    llvm = ensure_llvm()  # before Dr.Jit starts its LLVM back end
    with cached_syntax():  # Mitsuba's import and set_variant, fogpath's import: @dr.syntax
        import mitsuba as mi

        if name is None:
            current, env = mi.variant(), os.environ.get("FOGREF_VARIANT")
            source = (
                "mitsuba.variant() (set before fogref)"
                if current
                else "$FOGREF_VARIANT"
                if env
                else "fogref.set_variant"
            )
            name = params.choice(current or env or DEFAULT_VARIANT, "variant", VARIANTS, source)
        if name.startswith("llvm") and not llvm:
            raise FogrefError(HELP)
        if name.startswith("cuda") and not _has_cuda():
            raise FogrefError(NO_CUDA.format(name=name))
        if name not in mi.variants():
            raise FogrefError(f"Mitsuba variant '{name}' is not available; choose one of {mi.variants()}")
        if mi.variant() != name:
            try:
                mi.set_variant(name)
            except Exception as e:  # CUDA without a GPU, a broken LLVM, ...
                raise FogrefError(f"cannot use Mitsuba variant '{name}': {e}") from e
        if name not in _registered:
            fogref_plugins.register()  # its modules import Mitsuba: after the variant is set
            _registered.add(name)
    return name
