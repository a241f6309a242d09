#!/usr/bin/env bash
# The main job on the default scene: set up, path-trace the ground truth of
# scenes/valley.xml to out/valley.exr (+ PNG preview), then run the Unreal study
# (comparison report, error budget, fitted lobe) into reports/unreal_study/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
SPP=${SPP:-64}
.venv/bin/fogref render scenes/valley.xml --spp "$SPP" --seed 0 --out out/valley.exr
.venv/bin/fogref study out/valley.exr --out reports/unreal_study
