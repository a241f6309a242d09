#!/usr/bin/env bash
# REWRITES the committed reports of the main job: reports/unreal_study/ (the Unreal study of
# the default scene, 64 spp, seed 0), reports/fit/ (the lobe table, the engines fit table and its
# engine snippets) and reports/engines/ (the truth against the real web engines). Commit the result with
# a message that says which renderer made it. The other folders of reports/ are written by the
# scripts in benchmarks/ (each report names its command; see benchmarks/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
SPP=${SPP:-64}
echo "regenerate_reports: rewriting reports/unreal_study/, reports/fit/ and reports/engines/"
.venv/bin/fogref render scenes/valley.xml --spp "$SPP" --seed 0 --out out/valley.exr
.venv/bin/fogref study out/valley.exr --out reports/unreal_study --renders out/study
.venv/bin/fogref fit --scene scenes/valley.xml --lobe-table --out reports/fit
.venv/bin/python scripts/fit_table.py --scene scenes/valley.xml --out reports/fit   # engines.md + snippets/
.venv/bin/python scripts/make_html_examples.py --truth out/valley.exr   # report.html pages + screenshots
.venv/bin/python scripts/engine_table.py --out reports/engines   # the truth against the real web engines (Chromium)
git status --short reports/
