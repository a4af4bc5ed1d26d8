#!/usr/bin/env bash
# Refine by gain against run's former default (4 spp, a 2 % budget), and
# against 4 more spp everywhere, which with refine by gain is run's default
# since 2026-12-05 (bench/results/refine_gain.md). Never pass/fail.
#   [SIZE=WxH] bench/refine/gain.sh [OUT_DIR]      (default /tmp/modestack-refine-gain)
# Needs a built modestack (MODESTACK, default build/app/modestack) and Debian's
# python3-numpy and python3-openimageio. About 15 minutes on 2 cores at the
# default SIZE=128x96; about an hour at 320x240 (run's default size).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/../common.sh"
bench_require_packages python3-numpy python3-openimageio
modestack=$(realpath "${MODESTACK:-$here/../../build/app/modestack}")
out=${1:-/tmp/modestack-refine-gain}
mkdir -p "$out" && cd "$out"
size=${SIZE:-128x96}
for scene in orbit switch; do
  "$modestack" run --scene $scene --size $size --spp 4 --budget 2 --reference-spp 256 -q -o budget-$scene
  "$modestack" render --scene $scene --size $size --spp 256 --seed 4 -q -o ref2-$scene/$scene.####.exr
  "$modestack" run --scene $scene --size $size --spp 4 --by-gain -q -o gain-$scene
  "$modestack" run --scene $scene --size $size --spp 8 --by-gain -q -o spp8-$scene  # the default
  for run in budget gain spp8; do
    echo "== $scene $run: $(python3 -c "import json; j = json.load(open('$run-$scene/summary.json')); print(j['percent_pixels_refined'], '% re-rendered;', j['seconds'])")"
    /usr/bin/python3 "$here/score_run.py" $run-$scene budget-$scene/reference
    /usr/bin/python3 "$here/net_error.py" $run-$scene budget-$scene/reference ref2-$scene $scene
  done
done
