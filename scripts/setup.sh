#!/usr/bin/env bash
# Create .venv and install fogref with everything it needs, on a fresh machine: the exact
# versions of requirements.lock, then fogref itself (editable, no further dependencies).
# Installs Debian's libllvm19 when no LLVM >= 16 is present (Dr.Jit's LLVM back end
# aborts with LLVM 15 on AVX-512 CPUs and refuses LLVM 14), and Debian's chromium and
# chromium-driver for the browser tests of the HTML reports (skipped without them).
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

# the HTML reports' browser tests (tests/test_html_browser.py) drive Debian's headless Chromium
# through chromium-driver; without them those tests skip, saying so
if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    echo "setup: installing chromium and chromium-driver (the browser tests of the HTML reports)"
    { apt-get update -qq \
      && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null; } \
      || echo "setup: chromium could not be installed; the browser tests will skip" >&2
  else
    echo "setup: no chromium/chromedriver; the browser tests will skip" \
      "(install them with 'sudo apt-get install chromium chromium-driver')" >&2
  fi
fi

# the web engines (three.js, Babylon.js, PlayCanvas, Filament) at the versions of package-lock.json,
# for the tests and `fogref engine` that render them in headless Chromium; pages load them from
# node_modules/ through file://, nothing is fetched at run time
if ! command -v npm >/dev/null; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    echo "setup: installing nodejs and npm (the web engines)"
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs npm >/dev/null; } \
      || echo "setup: npm could not be installed; the engine tests will skip" >&2
  else
    echo "setup: no npm; the engine tests will skip (install Node.js and npm)" >&2
  fi
fi
if command -v npm >/dev/null && ! cmp -s package-lock.json node_modules/.fogref-package-lock.json; then
  npm ci --no-audit --no-fund --loglevel=error >/dev/null
  cp package-lock.json node_modules/.fogref-package-lock.json
fi

PY=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$PY" -m venv .venv
# what the installs below depend on: the interpreter, this checkout's place, the lock and
# pyproject.toml, and site-packages as the last setup left it (a package installed or removed
# since changes its folder's time).  When a finished setup recorded the same, the installs are
# skipped (pip's passes that find nothing to do, and the editable build, which runs every time).
stamp=.venv/.fogref-setup
setup_inputs() {
  .venv/bin/python -c 'import os, sys, sysconfig
print(sys.version, os.getcwd(), os.stat(sysconfig.get_paths()["purelib"]).st_mtime_ns)'
  cat requirements.lock pyproject.toml | sha256sum
}
if [ "$(cat "$stamp" 2>/dev/null)" != "$(setup_inputs)" ]; then
  rm -f "$stamp"
  .venv/bin/python -m pip install -q --upgrade pip
  # the locked versions (ruff, mypy, pytest included), then fogref on top of them
  .venv/bin/python -m pip install -q -r requirements.lock
  .venv/bin/python -m pip install -q --no-deps -e .
fi
# fogref and its plugins as bytecode: an editable install writes none, and where
# PYTHONDONTWRITEBYTECODE is set Python never writes it, so every fresh `fogref` process would
# compile its ~75 modules from source (0.2 s of CPU; reports/benchmarks/render_driver_startup.md)
.venv/bin/python -m compileall -q fogref plugins >/dev/null
.venv/bin/python -m pip check >/dev/null || {
  echo "setup: requirements.lock lacks a dependency of pyproject.toml; regenerate it (CONTRIBUTING.md)" >&2
  .venv/bin/python -m pip check >&2
  exit 1
}
echo "setup: ok ($(.venv/bin/python -c 'import mitsuba; print("mitsuba", mitsuba.__version__)'))"
setup_inputs > "$stamp"
