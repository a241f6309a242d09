#!/usr/bin/env bash
# Pack what the lent GPU machine lacks into .gpu/ (ignored by git; a device run carries it).
#
# That machine runs its own image's python3 (3.12, with numpy, Pillow and matplotlib) and can
# reach no package index, so Mitsuba, Dr.Jit and OpenEXR travel as one tar.xz of their unpacked
# wheels, at requirements.lock's versions.  Mitsuba's wheel is 62 MB; each of its variants is a
# separate extension module, so keeping only the ones the GPU script uses (cuda_ad_rgb, plus
# llvm_ad_rgb for the side-by-side CPU figures and scalar_rgb) and dropping its C++ headers
# brings the pack to about 30 MB, under the 64 MiB a device run may carry with the tree.
#
# Usage: bash scripts/gpu_pack.sh [PYTHON_VERSION]   (default 3.12; 3.11 packs for this machine,
#        to try scripts/gpu_bench.sh here on the CPU)
# Needs network access to PyPI (this machine has it; the GPU machine does not).
set -euo pipefail
cd "$(dirname "$0")/.."
py=${1:-3.12}
keep="cuda_ad_rgb llvm_ad_rgb scalar_rgb"
pin() { grep -i "^$1==" requirements.lock | head -1; }
pins="$(pin mitsuba) $(pin drjit) $(pin OpenEXR)"
[ "$(echo $pins | wc -w)" = 3 ] || { echo "gpu_pack: requirements.lock lacks a pin of mitsuba, drjit or OpenEXR" >&2; exit 1; }
pip=.venv/bin/pip
[ -x "$pip" ] || pip="python3 -m pip"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
$pip download -q --no-deps --only-binary=:all: --python-version "$py" \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 -d "$tmp/wheels" $pins
mkdir "$tmp/site"
for w in "$tmp"/wheels/*.whl; do python3 -m zipfile -e "$w" "$tmp/site"; done
tag="cpython-${py/./}"
for so in "$tmp"/site/mitsuba/{cuda,llvm,scalar}_*."$tag"-*.so; do  # one module per variant
  v=$(basename "$so"); v=${v%%.*}
  case " $keep " in *" $v "*) ;; *) rm "$so" ;; esac
done
rm -rf "$tmp/site/mitsuba/include"
chmod -R u+w,a+r "$tmp/site"
mkdir -p .gpu
out=.gpu/site-cp${py/./}.tar.xz
XZ_OPT=-9 tar -cJf "$out.tmp" -C "$tmp/site" .
mv "$out.tmp" "$out"
echo "gpu_pack: $out ($(du -h "$out" | cut -f1)): $pins; Mitsuba variants kept: $keep"
