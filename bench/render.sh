#!/usr/bin/env bash
# Benchmark of `modestack render` against Embree's own path tracer tutorial
# (`pathtracer` from Debian's embree-tools) on the same room (issue 5). Not a
# test: it never fails on time.
#
# Both render frame 1 of the built-in `static` scene (a closed Cornell-style room,
# two boxes, 36 triangles + the 2-triangle light quad) at 1920x1080, SPP samples
# per pixel (default 4), at most DEPTH bounces (default 8; Embree's
# --max-path-length counts the same way: 1 = primary hit + shadow ray), with 1
# and 2 threads, REPEATS times each (default 3). bench_export_scene writes the
# room as .obj + an .ecs of Embree options (camera, and a point light where our
# quad light is: see bench/export_scene.cpp).
#
# Ours: paths/s and rays/s from --json (render time only), and paths per second
# of process wall time (which includes writing all 27 AOV channels as EXR).
# Embree: --benchmark 0 1 renders one frame and prints its fps and Mrays/s;
# paths/s = fps × width × height × spp. Prints Markdown tables (also in
# $BENCH_DIR/results/render.md), raw runs in $BENCH_DIR/results/render.tsv.
#
# Paths per CPU second (process CPU time) is the per-core rate that survives a
# shared machine; "cores obtained" (CPU / wall) says whether a 2-thread run got
# 2 cores, without which the scaling figure means nothing.
#
# Environment: BENCH_DIR (default /tmp/modestack-bench), BUILD_DIR (default
# $BENCH_DIR/build), REPEATS, SIZE (1920x1080), SPP, DEPTH, SCENE (static),
# REPORT_ONLY=1 (rebuild the tables from the last run's results).
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/common.sh

bench_dir=${BENCH_DIR:-/tmp/modestack-bench}
build_dir=${BUILD_DIR:-$bench_dir/build}
repeats=${REPEATS:-3}
size=${SIZE:-1920x1080}
spp=${SPP:-4}
depth=${DEPTH:-8}
scene=${SCENE:-static}
results=$bench_dir/results
room=$bench_dir/embree-room
mkdir -p "$results" "$room"

scripts/install-deps
bench_require_packages time jq embree-tools
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMODESTACK_BUILD_TESTS=OFF \
    -DMODESTACK_BUILD_BENCH=ON >/dev/null
cmake --build "$build_dir" --target modestack bench_export_scene >/dev/null
modestack=$build_dir/app/modestack
embree=$(command -v pathtracer || true)
[[ -x $embree ]] || embree=/usr/bin/pathtracer
read -r width height < <(echo "$size" | tr x ' ')
triangles=$("$build_dir/bench/bench_export_scene" "$scene" 1 "$room" | jq -r .triangles)

tsv=$results/render.tsv
[[ ${REPORT_ONLY:-0} == 1 ]] || : >"$tsv"
for run in $(seq 1 "$repeats"); do
    [[ ${REPORT_ONLY:-0} == 1 ]] && break
    for threads in 1 2; do
        out=$bench_dir/render-out
        rm -rf "$out"
        json=$results/render-ours-$threads.$run.json
        bench_time "$tsv" "ours-$threads" "$run" "$modestack" render --scene "$scene" --frames 1 --size "$size" \
            --spp "$spp" --max-depth "$depth" --threads "$threads" -q -o "$out/frame.####.exr" --json "$json"
        rm -rf "$out"
        log=$results/render-embree-$threads.$run.log
        (cd "$room" && bench_time "$tsv" "embree-$threads" "$run" "$embree" -c room.ecs --size "$width" "$height" \
            --spp "$spp" --max-path-length "$depth" --threads "$threads" --benchmark 0 1 >"$log" 2>&1)
    done
done

# rates LABEL THREADS: one line per run "paths_per_s rays_per_s paths_per_wall_s
# cores_used paths_per_cpu_s".
rates()
{
    local label=$1 threads=$2 run wall cpu
    for run in $(seq 1 "$repeats"); do
        read -r wall cpu < <(awk -F'\t' -v l="$label-$threads" -v r="$run" '$1 == l && $2 == r { print $3, $4 + $5 }' "$tsv")
        if [[ $label == ours ]]; then
            jq -r --arg wall "$wall" --arg cpu "$cpu" \
                '"\(.paths_per_second) \(.rays_per_second) \(.paths / ($wall | tonumber)) \(($cpu | tonumber) / ($wall | tonumber)) \(.paths / ($cpu | tonumber))"' \
                "$results/render-ours-$threads.$run.json"
        else
            awk -v w="$width" -v h="$height" -v s="$spp" -v wall="$wall" -v cpu="$cpu" '
                /^BENCHMARK_RENDER_AVG / { fps = $2 } /^BENCHMARK_RENDER_MRAYPS_AVG / { mrays = $2 }
                END { print fps * w * h * s, mrays * 1e6, w * h * s / wall, cpu / wall, w * h * s / cpu }' \
                "$results/render-embree-$threads.$run.log"
        fi
    done
}

# column N of rates → "max median" (rates: the max is the least disturbed run).
rate_stats()
{
    awk -v c="$1" '{ print $c }' | sort -g | awk '{ v[NR] = $1 } END {
        median = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2; print v[NR], median }'
}

report=$results/render.md
{
    echo "### modestack render vs Embree pathtracer"
    echo
    echo "Machine: $(bench_machine)."
    echo "Source: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' + uncommitted changes'); Embree $(dpkg-query -W -f='${Version}' embree-tools)."
    echo "Scene: '$scene' frame 1, ${width}x${height}, $spp spp, max depth $depth, $triangles triangles (+ light)."
    echo "Rates: best / median of $repeats runs (shared machine: the best run is the least disturbed)."
    echo
    echo "| renderer | threads | Mpaths/s (best / med) | Mpaths/s per thread | Mrays/s (best / med) | rays per path | Mpaths per process wall s (best) | Mpaths per process CPU s (best / med) | cores obtained (CPU / wall, med) |"
    echo "|---|---|---|---|---|---|---|---|---|"
    declare -A best best_cpu
    for label in ours embree; do
        for threads in 1 2; do
            lines=$(rates "$label" "$threads")
            read -r paths_best paths_median < <(echo "$lines" | rate_stats 1)
            read -r rays_best rays_median < <(echo "$lines" | rate_stats 2)
            read -r wall_best _ < <(echo "$lines" | rate_stats 3)
            read -r cores_best cores_median < <(echo "$lines" | rate_stats 4)
            read -r cpu_best cpu_median < <(echo "$lines" | rate_stats 5)
            best[$label-$threads]=$paths_best
            best_cpu[$label-$threads]=$cpu_best
            printf '| %s | %s | %.3f / %.3f | %.3f | %.2f / %.2f | %.2f | %.3f | %.3f / %.3f | %.2f |\n' "$label" "$threads" \
                "$(awk -v v="$paths_best" 'BEGIN { print v / 1e6 }')" "$(awk -v v="$paths_median" 'BEGIN { print v / 1e6 }')" \
                "$(awk -v v="$paths_best" -v t="$threads" 'BEGIN { print v / 1e6 / t }')" \
                "$(awk -v v="$rays_best" 'BEGIN { print v / 1e6 }')" "$(awk -v v="$rays_median" 'BEGIN { print v / 1e6 }')" \
                "$(awk -v r="$rays_median" -v p="$paths_median" 'BEGIN { print r / p }')" \
                "$(awk -v v="$wall_best" 'BEGIN { print v / 1e6 }')" \
                "$(awk -v v="$cpu_best" 'BEGIN { print v / 1e6 }')" "$(awk -v v="$cpu_median" 'BEGIN { print v / 1e6 }')" \
                "$cores_median"
        done
    done
    echo
    printf 'Ours / Embree paths/s per core: %.2f with 1 thread, %.2f with 2 threads (target >= 1.0).\n' \
        "$(awk -v a="${best[ours-1]}" -v b="${best[embree-1]}" 'BEGIN { print a / b }')" \
        "$(awk -v a="${best[ours-2]}" -v b="${best[embree-2]}" 'BEGIN { print a / b }')"
    printf 'Ours / Embree paths per CPU second (contention-robust per-core rate; ours includes writing the AOVs): %.2f with 1 thread, %.2f with 2 threads.\n' \
        "$(awk -v a="${best_cpu[ours-1]}" -v b="${best_cpu[embree-1]}" 'BEGIN { print a / b }')" \
        "$(awk -v a="${best_cpu[ours-2]}" -v b="${best_cpu[embree-2]}" 'BEGIN { print a / b }')"
    printf 'Scaling 1 -> 2 threads: ours %.2fx, Embree %.2fx (target >= 1.8x; only meaningful when the run obtained 2 cores, see the last column).\n' \
        "$(awk -v a="${best[ours-2]}" -v b="${best[ours-1]}" 'BEGIN { print a / b }')" \
        "$(awk -v a="${best[embree-2]}" -v b="${best[embree-1]}" 'BEGIN { print a / b }')"
} >"$report"
cat "$report"
