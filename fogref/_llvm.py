"""Find an LLVM >= 16 for Dr.Jit's llvm_* variants, before drjit is imported.

On AVX-512 CPUs Dr.Jit aborts with LLVM 15 (``Cannot select ... fmaximum``) and
refuses LLVM 14, so we look for libLLVM 16 or newer and set
``DRJIT_LIBLLVM_PATH``.  ``scripts/setup.sh`` installs Debian's ``libllvm19``.
"""

from __future__ import annotations

import glob
import os
import re

_SEARCH = [
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib",
    "/usr/local/opt/llvm/lib/libLLVM*.dylib",
]

MIN_MAJOR = 16
HELP = (
    "fogref: no LLVM >= 16 found for Dr.Jit's llvm_* variants (LLVM 15 crashes on "
    "AVX-512 CPUs, LLVM 14 is too old). Install one, e.g. `apt-get install libllvm19` "
    "on Debian/Ubuntu, or set DRJIT_LIBLLVM_PATH=/path/to/libLLVM.so."
)


def _major(path: str) -> int:
    name = os.path.basename(path)
    m = re.search(r"LLVM(?:-|\.so\.)(\d+)", name) or re.search(r"llvm-(\d+)", path)
    return int(m.group(1)) if m else -1


def find_llvm() -> str | None:
    """Path of the newest libLLVM >= 16 on this machine, or None."""
    found = []
    for pattern in _SEARCH:
        for p in glob.glob(pattern):
            if os.path.isfile(p) and _major(p) >= MIN_MAJOR:
                found.append((_major(p), p))
    return max(found)[1] if found else None


def ensure_llvm() -> str | None:
    """Set DRJIT_LIBLLVM_PATH if unset; returns the path used (None if none)."""
    path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if path:
        return path
    path = find_llvm()
    if path:
        os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path
