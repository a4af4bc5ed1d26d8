#!/usr/bin/env bash
# Long shots (issue 31, item 4): `modestack denoise` with default options on a
# 1920x1080 RGB half ZIP sequence of 100 and of 1000 frames, to show that
# memory stays bounded (peak RSS within --max-memory, whose default is a quarter
# of the machine's) and how the time per frame grows with the shot's length.
# Not a test: it never fails on time.
#
#   bench/long_shot.sh MODESTACK MAKE_NOISY_SEQUENCE [WORK]
# MODESTACK and MAKE_NOISY_SEQUENCE are built binaries (app/modestack and
# bench/bench_make_noisy_sequence of a -DMODESTACK_BUILD_BENCH=ON build).
# Environment: LENGTHS ("100 1000"), SIZE (1920x1080), MAX_MEMORY (empty: the
# default), EXTRA (more denoise options).
# Disk: about 9 MB per input frame and 13 MB per output frame at 1080p; the
# inputs are kept in WORK between runs, each output is removed after its run.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
modestack=${1:?usage: long_shot.sh MODESTACK MAKE_NOISY_SEQUENCE [WORK]}
make_sequence=${2:?usage: long_shot.sh MODESTACK MAKE_NOISY_SEQUENCE [WORK]}
work=${3:-/tmp/modestack-long-shot}
lengths=${LENGTHS:-100 1000}
size=${SIZE:-1920x1080}
bench_require_packages time jq
mkdir -p "$work"
tsv=$work/long_shot.tsv
: >"$tsv"

echo "| frames | wall s | CPU s | CPU s per frame | peak RSS MB | --max-memory MB | solver | passes | in memory | band rows | N |"
echo "|---:|---:|---:|---:|---:|---:|---|---:|---|---:|---:|"
for frames in $lengths; do
    data=$work/noisy-$size-$frames
    if [[ ! -f $data/made ]]; then
        rm -rf "$data"
        mkdir -p "$data"
        "$make_sequence" --size "$size" --frames "$frames" --seed 1 --noise 0.35 -o "$data/noisy.%04d.exr" >/dev/null
        touch "$data/made"
    fi
    out=$work/out-$frames
    rm -rf "$out"
    options=()
    [[ -n ${MAX_MEMORY:-} ]] && options+=(--max-memory "$MAX_MEMORY")
    # shellcheck disable=SC2206
    [[ -n ${EXTRA:-} ]] && options+=($EXTRA)
    bench_time "$tsv" "denoise-$frames" 1 "$modestack" denoise "$data/noisy.%04d.exr" -o "$out/denoised.%04d.exr" \
        --json "$work/denoise-$frames.json" -q "${options[@]}"
    rm -rf "$out"
    read -r _ _ wall user sys rss < <(grep "^denoise-$frames" "$tsv" | tail -n 1)
    json=$work/denoise-$frames.json
    awk -v f="$frames" -v w="$wall" -v u="$user" -v s="$sys" -v r="$rss" \
        -v m="$(jq -r '.max_memory_bytes / 1048576 | floor' "$json")" -v solver="$(jq -r '.solver' "$json")" \
        -v passes="$(jq -r '.passes' "$json")" -v kept="$(jq -r '.in_memory' "$json")" \
        -v band="$(jq -r '.band_rows' "$json")" -v rank="$(jq -r '.rank.n' "$json")" \
        'BEGIN { printf "| %d | %.1f | %.1f | %.3f | %.0f | %s | %s | %s | %s | %s | %s |\n",
                 f, w, u + s, (u + s) / f, r / 1024, m, solver, passes, kept, band, rank }'
done
