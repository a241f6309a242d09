#!/usr/bin/env bash
# The main job on the default scene: set up, path-trace the ground truth of
# scenes/valley.xml to out/valley.exr (+ PNG preview), then run the Unreal study
# (comparison report, error budget, fitted lobe) into out/unreal_study/.
# Everything it writes is under out/ (git-ignored): the checkout stays clean.
# The committed reports/ are regenerated only by scripts/regenerate_reports.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
SPP=${SPP:-64}
.venv/bin/fogref render scenes/valley.xml --spp "$SPP" --seed 0 --out out/valley.exr
.venv/bin/fogref study out/valley.exr --out out/unreal_study --renders out/study
