"""Find an LLVM >= 16 for Dr.Jit's ``llvm_*`` variants, before Dr.Jit starts it.

Dr.Jit loads ``libLLVM`` when its LLVM back end starts (the first LLVM array or
``mi.set_variant("llvm_...")``), from ``$DRJIT_LIBLLVM_PATH`` if set, else from
the library search path. On AVX-512 CPUs Dr.Jit 1.5 aborts with LLVM 15 on the
first ``dr.maximum``/``dr.minimum`` (``LLVM ERROR: Cannot select ... fmaximum``)
and it refuses LLVM 14 as too old, so fogref looks for libLLVM 16 or newer and
sets ``DRJIT_LIBLLVM_PATH``. ``scripts/setup.sh`` installs Debian's
``libllvm19`` where it may.

Nothing here runs on import: :func:`fogref.set_variant` and
:func:`fogref.ensure_llvm` call :func:`require_llvm`.
"""

from __future__ import annotations

import glob
import os
import re

from fogref.errors import FogrefError

#: The Mitsuba variant fogref sets when none is set (:func:`fogref.set_variant`, and the sky
#: evaluation of :mod:`fogref.media.sky`, which runs below the render floor).
DEFAULT_VARIANT = "llvm_ad_rgb"

_SEARCH = [
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib",
    "/usr/local/opt/llvm/lib/libLLVM*.dylib",
]

#: the oldest LLVM major version fogref hands to Dr.Jit.
MIN_MAJOR = 16
HELP = (
    "fogref: no LLVM >= 16 found for Dr.Jit's llvm_* variants (LLVM 15 crashes on "
    "AVX-512 CPUs, LLVM 14 is too old). Install one, e.g. `apt-get install libllvm19` "
    "on Debian/Ubuntu, or set DRJIT_LIBLLVM_PATH=/path/to/libLLVM.so."
)


def llvm_major(path: str) -> int:
    """LLVM major version named by a library path, or -1 if the name has none.

    Examples
    --------
    >>> llvm_major("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
    19
    >>> llvm_major("/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1")
    15
    >>> llvm_major("/usr/lib/llvm-17/lib/libLLVM.so")
    17
    >>> llvm_major("/usr/local/lib/libLLVM.so")
    -1
    """
    name = os.path.basename(path)
    m = re.search(r"LLVM(?:-|\.so\.)(\d+)", name) or re.search(r"llvm-(\d+)", path)
    return int(m.group(1)) if m else -1


def find_llvm() -> str | None:
    """Path of the newest libLLVM >= :data:`MIN_MAJOR` on this machine, or None.

    Looks only in the usual Debian/Ubuntu, Fedora, /usr/local and Homebrew
    folders (``_SEARCH``); files whose names carry no version are skipped.
    """
    found = []
    for pattern in _SEARCH:
        for p in glob.glob(pattern):
            if os.path.isfile(p) and llvm_major(p) >= MIN_MAJOR:
                found.append((llvm_major(p), p))
    return max(found)[1] if found else None


def ensure_llvm() -> str | None:
    """Set ``$DRJIT_LIBLLVM_PATH`` if unset; the path in use, or None if none was found.

    A value the user set is kept as it is.
    """
    path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if path:
        return path
    path = find_llvm()
    if path:
        os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path


def require_llvm() -> str:
    """:func:`ensure_llvm`, raising :class:`~fogref.errors.FogrefError` (:data:`HELP`) if none."""
    path = ensure_llvm()
    if not path:
        raise FogrefError(HELP)
    return path
