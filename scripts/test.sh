#!/usr/bin/env bash
# Set up (if needed) and run the test suite at low sample counts.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/python -m pytest -q --durations=25 "$@"
