#!/usr/bin/env bash
# Object space against image space at film sizes (issue 31 item 2): time and
# peak RSS of `denoise --object-space` and of the image-space default on the
# same frames. Not a test: it never fails on speed.
#
# Renders the built-in `flythrough` at SIZE (default 640x480; FRAMES, default
# 1-48) at 4 spp with `render --points` (kept and reused for the same SIZE and
# FRAMES: at 1920x1080 the bake of 2 M points takes most of an hour on 2 cores),
# then denoises its DiffInd RUNS times each way (default 2, alternated) and
# prints min and median wall seconds, the surface filter's own seconds and peak
# RSS, as rows for bench/results/object_space.md.
# Environment: SCALE_DIR (work files, default /tmp/modestack-object-scale),
# BUILD_DIR (default build; must hold a Release app/modestack), SIZE, FRAMES, RUNS,
# OBJECT_OPTIONS (more options for the object-space run, e.g. --max-memory 2G).
set -euo pipefail
cd "$(dirname "$0")/../.."
work=${SCALE_DIR:-/tmp/modestack-object-scale}
modestack=${BUILD_DIR:-build}/app/modestack
size=${SIZE:-640x480}
frames=${FRAMES:-1-48}
runs=${RUNS:-2}
read -r -a object_options <<<"${OBJECT_OPTIONS:-}"
source bench/common.sh
[[ -x $modestack ]] || { echo "scale.sh: no $modestack: build Release first (scripts/build)" >&2; exit 1; }
shot=$work/$size-$frames
mkdir -p "$shot"
if [[ ! -f $shot/rendered ]]; then
    rm -rf "$shot/noisy" "$shot/points"
    "$modestack" render --scene flythrough --size "$size" --frames "$frames" --spp 4 --seed 1 -q \
        --points "$shot/points/p.####.exr" -o "$shot/noisy/n.####.exr"
    touch "$shot/rendered"
fi
tsv=$shot/times.tsv
: >"$tsv"
for ((run = 1; run <= runs; run++)); do
    rm -rf "$shot/image" "$shot/object"
    bench_time "$tsv" image "$run" "$modestack" denoise "$shot/noisy/n.####.exr" --layer DiffInd -q \
        -o "$shot/image/d.####.exr"
    bench_time "$tsv" object "$run" "$modestack" denoise "$shot/noisy/n.####.exr" --layer DiffInd -q \
        --object-space "$shot/points/p.####.exr" "${object_options[@]}" -o "$shot/object/d.####.exr" \
        --json "$shot/object.json"
done
filter_seconds=$(/usr/bin/python3 -c "import json,sys; print(round(json.load(open(sys.argv[1]))['surface_filter']['seconds'], 2))" "$shot/object.json" 2>/dev/null || echo "?")
points=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['object_space']['points'])" "$shot/object.json" 2>/dev/null || echo "?")
echo "| flythrough $size frames $frames, $points points | way | wall s (min / median) | peak RSS MB |"
for way in image object; do
    awk -F'\t' -v way="$way" '$1 == way { print $3, $6 }' "$tsv" | sort -n | awk -v way="$way" '
        { wall[NR] = $1; if ($2 > rss) rss = $2 }
        END { printf "| | %s | %.1f / %.1f | %.0f |\n", way, wall[1], wall[int((NR + 1) / 2)], rss / 1024 }'
done
echo "surface filter (last object-space run): $filter_seconds s; $(date -u +%F), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
