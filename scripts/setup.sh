#!/usr/bin/env bash
# Create .venv and install fogref with everything it needs, on a fresh machine: the exact
# versions of requirements.lock, then fogref itself (editable, no further dependencies).
# Installs Debian's libllvm19 when no LLVM >= 16 is present (Dr.Jit's LLVM back end
# aborts with LLVM 15 on AVX-512 CPUs and refuses LLVM 14).
set -euo pipefail
cd "$(dirname "$0")/.."

have_llvm() {
  ls /usr/lib/*/libLLVM*.so* /usr/lib/llvm-*/lib/libLLVM*.so* 2>/dev/null \
    | grep -Eq 'LLVM(-|\.so\.)?(1[6-9]|[2-9][0-9])'
}
if ! have_llvm && [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    echo "setup: installing libllvm19 (Dr.Jit needs LLVM >= 16)"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
  else
    echo "setup: no LLVM >= 16 found. Install one (e.g. 'sudo apt-get install libllvm19')" >&2
    echo "       or set DRJIT_LIBLLVM_PATH=/path/to/libLLVM.so" >&2
    exit 1
  fi
fi

PY=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$PY" -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
# the locked versions (ruff, mypy, pytest included), then fogref on top of them
.venv/bin/python -m pip install -q -r requirements.lock
.venv/bin/python -m pip install -q --no-deps -e .
.venv/bin/python -m pip check >/dev/null || {
  echo "setup: requirements.lock lacks a dependency of pyproject.toml; regenerate it (CONTRIBUTING.md)" >&2
  .venv/bin/python -m pip check >&2
  exit 1
}
echo "setup: ok ($(.venv/bin/python -c 'import mitsuba; print("mitsuba", mitsuba.__version__)'))"
