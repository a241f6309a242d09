#!/usr/bin/env bash
# The GPU figures of reports/benchmarks/gpu.md, as one prepared run on a lent GPU machine.
#
# Here:   bash scripts/gpu_pack.sh         (once: .gpu/site-cp312.tar.xz, about 30 MB)
# Device, in two runs (each under a run's 600 s; on one H200 about 300 s and 410 s):
#   run(command='STEPS="import driver" bash scripts/gpu_bench.sh', carry=[".gpu/site-cp312.tar.xz"], timeout_s=450)
#   run(command='STEPS="import ladder attribution" bash scripts/gpu_bench.sh', carry=[...], timeout_s=480)
# Try it here on the CPU first (same steps, tiny sizes, the 3.11 pack, llvm_ad_rgb; the pack holds
# Mitsuba, Dr.Jit and OpenEXR, and the python must bring NumPy, Pillow and matplotlib, as the
# device image's does and the venv's does here):
#         bash scripts/gpu_pack.sh 3.11 && PYTHON=.venv/bin/python OUT=/tmp/gpu-out bash scripts/gpu_bench.sh --cpu-smoke
#
# STEPS picks steps (default: all, "import driver ladder attribution"); LADDER_SCENES passes
# --scenes to the ladder (default: all four).
#
# Every step has its own time limit so that a slow one leaves the others their time, and each
# writes its report into $OUT as soon as it ends (a device run returns the files under $OUT).
set -uo pipefail
cd "$(dirname "$0")/.."
: "${OUT:?OUT must name the folder for the reports}"
mkdir -p "$OUT"
smoke=0; [ "${1:-}" = --cpu-smoke ] && smoke=1
py=${PYTHON:-python3}  # the device image's python3 (3.12, with numpy, Pillow, matplotlib)
tag=$($py -c 'import sys; print(f"cp{sys.version_info[0]}{sys.version_info[1]}")')
$py -c 'import numpy, PIL, matplotlib' 2>/dev/null || {
  echo "gpu_bench: $py lacks NumPy, Pillow or matplotlib, which the pack leaves to the python (PYTHON=...)" >&2
  exit 1
}
site=$(mktemp -d)
tar -xJf ".gpu/site-$tag.tar.xz" -C "$site" || { echo "gpu_bench: no .gpu/site-$tag.tar.xz (run scripts/gpu_pack.sh)" >&2; exit 1; }
ln -s "$PWD/plugins" "$site/fogref_plugins"  # the installed name of plugins/ (pyproject.toml)
export PYTHONPATH="$site:$PWD"
log="$OUT/gpu_bench.log"
steps=" ${STEPS:-import driver ladder attribution} "
scenes=${LADDER_SCENES:+--scenes $LADDER_SCENES}
step() {  # step SECONDS NAME COMMAND...: run with a limit, log its time and exit status
  local limit=$1 name=$2; shift 2
  case $steps in *" $name "*) ;; *) return ;; esac
  local t0=$SECONDS
  echo "== $name (limit ${limit}s)" | tee -a "$log"
  timeout "$limit" "$@" >>"$log" 2>&1
  echo "== $name: exit $? after $((SECONDS - t0)) s" | tee -a "$log"
}
{ date -u; uname -a; $py -VV; nvidia-smi 2>&1 | head -15; } >"$log"
if [ $smoke = 1 ]; then
  variant=llvm_ad_rgb
  step 60 import $py -c "import mitsuba as mi, drjit as dr; mi.set_variant('$variant'); print(mi.__version__, dr.__version__)"
  step 300 driver $py benchmarks/render_driver.py --variant $variant --quick --out "$OUT/render_driver_gpu"
  step 300 ladder env FOGREF_VARIANT=$variant $py benchmarks/time_vs_error.py --quick ${scenes:---scenes valley} --max-spp 4 --out "$OUT/ladder"
  step 120 attribution $py benchmarks/gpu_attribution.py --variant $variant --case 64x36x4 --out "$OUT/attribution"
else
  variant=cuda_ad_rgb
  step 60 import $py -c "import mitsuba as mi, drjit as dr; mi.set_variant('$variant'); print(mi.__version__, dr.__version__)"
  # fogref render against one mi.render at 1920x1080, 1024 spp (target: within 1.1x; the whole
  # truth in 10 s or less), then the default scene's sizes of the CPU report for a ratio
  step 400 driver $py benchmarks/render_driver.py --variant $variant --repeats 2 \
    --cases 1920x1080x1024,320x180x64 --out "$OUT/render_driver_gpu"
  # the time-vs-error ladder at 320x180 on the GPU
  step 300 ladder env FOGREF_VARIANT=$variant $py benchmarks/time_vs_error.py --res 320 180 \
    --max-spp 256 --ref-spp 4096 $scenes --out "$OUT/ladder"
  # one option or the lanes per pass changed at a time, 1920x1080 at 64 spp, and render()'s profile
  step 120 attribution $py benchmarks/gpu_attribution.py --variant $variant --case 1920x1080x64 \
    --out "$OUT/attribution"
fi
ls -la "$OUT" >>"$log"
