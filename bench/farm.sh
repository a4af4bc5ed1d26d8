#!/usr/bin/env bash
# Benchmark of the farm split of `modestack denoise` (issue 11). Not a test: it
# never fails on time (it fails if the split runs' pixels differ from one run's).
#
# 1. Builds modestack and bench_make_noisy_sequence (Release) and makes a
#    1920x1080 RGB half ZIP sequence of FRAMES (48) noisy frames in $BENCH_DIR.
# 2. Times one process, `mpirun -n 1` and `mpirun -n 2` (2 ranks on this
#    2-core machine: they share its cores; `--bind-to none`, or Open MPI pins
#    each of 1 or 2 ranks to one core), and a five-stage farm job run task
#    after task: stats --rows 1/2 and 2/2, solve, survey and modes --rows 1/2
#    and 2/2, write --frames 1/2 and 2/2, and write --frames 1/4; also stats --rows 1/2
#    on the first half of the frames, so that the model can split a statistics
#    task into its per-frame (read, clean) and per-frame² (Gram) parts. Wall,
#    CPU, peak RSS (GNU time) per run.
# 3. Checks with idiff that the MPI and farm outputs hold the pixels of the
#    single run, frame by frame.
# Prints a Markdown table (also $BENCH_DIR/results/farm.md); raw runs in
# $BENCH_DIR/results/farm.tsv.
#
# Environment: BENCH_DIR (/tmp/modestack-bench), BUILD_DIR ($BENCH_DIR/build),
# FRAMES (48), SIZE (1920x1080), REPEATS (1).
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/common.sh

bench_dir=${BENCH_DIR:-/tmp/modestack-bench}
build_dir=${BUILD_DIR:-$bench_dir/build}
frames=${FRAMES:-48}
size=${SIZE:-1920x1080}
repeats=${REPEATS:-1}
results=$bench_dir/results
mkdir -p "$bench_dir" "$results"

scripts/install-deps
bench_require_packages time jq
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMODESTACK_BUILD_TESTS=OFF \
    -DMODESTACK_BUILD_BENCH=ON >/dev/null
cmake --build "$build_dir" --target modestack bench_make_noisy_sequence >/dev/null
modestack=$build_dir/app/modestack
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none

data=$bench_dir/noisy-$size-$frames
if [[ ! -f $data/made-with || $(cat "$data/made-with") != "$size $frames seed 1 noise 0.35" ]]; then
    rm -rf "$data"
    mkdir -p "$data"
    echo "bench: making $frames noisy frames of $size in $data" >&2
    "$build_dir/bench/bench_make_noisy_sequence" --size "$size" --frames "$frames" --seed 1 --noise 0.35 \
        -o "$data/noisy.%04d.exr" >/dev/null
    echo "$size $frames seed 1 noise 0.35" >"$data/made-with"
fi
input=$data/noisy.%04d.exr
work=$bench_dir/farm
tsv=$results/farm.tsv
: >"$tsv"

# same_pixels DIR_A DIR_B: every frame's pixels equal (idiff: 0 = identical).
same_pixels()
{
    local frame name
    for frame in $(seq 1 "$frames"); do
        name=$(printf 'd.%04d.exr' "$frame")
        idiff -q -fail 0 -failpercent 0 -warn 0 "$1/$name" "$2/$name" >/dev/null ||
            { echo "bench: $1/$name and $2/$name differ" >&2; return 1; }
    done
}

half=$((frames / 2))
for run in $(seq 1 "$repeats"); do
    rm -rf "$work"
    mkdir -p "$work"
    bench_time "$tsv" single "$run" "$modestack" denoise "$input" -q -o "$work/one/d.%04d.exr"
    bench_time "$tsv" mpirun-1 "$run" mpirun --bind-to none -n 1 "$modestack" denoise "$input" -q -o "$work/mpi1/d.%04d.exr"
    bench_time "$tsv" mpirun-2 "$run" mpirun --bind-to none -n 2 "$modestack" denoise "$input" -q -o "$work/mpi2/d.%04d.exr"
    bench_time "$tsv" stats-1/2 "$run" "$modestack" denoise "$input" -q --stage stats --rows 1/2 -o "$work/1.stats"
    bench_time "$tsv" stats-2/2 "$run" "$modestack" denoise "$input" -q --stage stats --rows 2/2 -o "$work/2.stats"
    bench_time "$tsv" solve "$run" "$modestack" denoise "$input" -q --stage solve --stats "$work/1.stats" \
        "$work/2.stats" -o "$work/shot.solve"
    bench_time "$tsv" survey-1/2 "$run" "$modestack" denoise "$input" -q --stage survey --solve "$work/shot.solve" \
        --rows 1/2 -o "$work/1.survey"
    bench_time "$tsv" survey-2/2 "$run" "$modestack" denoise "$input" -q --stage survey --solve "$work/shot.solve" \
        --rows 2/2 -o "$work/2.survey"
    surveyed=("$modestack" denoise "$input" -q --solve "$work/shot.solve" --survey "$work/1.survey" "$work/2.survey")
    bench_time "$tsv" modes-1/2 "$run" "${surveyed[@]}" --stage modes --rows 1/2 -o "$work/1.modes"
    bench_time "$tsv" modes-2/2 "$run" "${surveyed[@]}" --stage modes --rows 2/2 -o "$work/2.modes"
    write=("${surveyed[@]}" --stage write --modes "$work/1.modes" "$work/2.modes")
    bench_time "$tsv" write-1/2 "$run" "${write[@]}" --frames 1/2 -o "$work/farm/d.%04d.exr"
    bench_time "$tsv" write-2/2 "$run" "${write[@]}" --frames 2/2 -o "$work/farm/d.%04d.exr"
    bench_time "$tsv" write-1/4 "$run" "${write[@]}" --frames 1/4 -o "$work/quarter/d.%04d.exr"
    bench_time "$tsv" "stats-1/2-F$half" "$run" "$modestack" denoise "$input" -q --frames "1-$half" --stage stats \
        --rows 1/2 -o "$work/half.stats"
    same_pixels "$work/one" "$work/mpi1"
    same_pixels "$work/one" "$work/mpi2"
    same_pixels "$work/one" "$work/farm"
done
stats_bytes=$(stat -c %s "$work/1.stats")
solve_bytes=$(stat -c %s "$work/shot.solve")
modes_bytes=$(stat -c %s "$work/1.modes")
survey_bytes=$(stat -c %s "$work/1.survey")

report=$results/farm.md
{
    echo "### modestack denoise on a farm and under MPI"
    echo
    echo "Machine: $(bench_machine)."
    echo "Source: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' + uncommitted changes')."
    echo "Data: $frames frames of $size RGB half ZIP; default options (mode filter, auto rank, gram)."
    echo "Min of $repeats run(s). MPI and farm outputs: pixels identical to the single run (idiff, every frame)."
    echo "Stage files: statistics $((stats_bytes / 1024)) KiB per half, solve $((solve_bytes / 1024)) KiB, survey $((survey_bytes / 1024)) KiB and modes $((modes_bytes / 1048576)) MiB per half."
    echo
    echo "| run | wall s | CPU s | peak RSS MB | wall × single |"
    echo "|---|---|---|---|---|"
    read -r single _ < <(bench_stats "$tsv" single 3)
    for label in single mpirun-1 mpirun-2 stats-1/2 stats-2/2 solve survey-1/2 survey-2/2 modes-1/2 modes-2/2 \
        write-1/2 write-2/2 write-1/4 \
        "stats-1/2-F$half"; do
        read -r wall _ < <(bench_stats "$tsv" "$label" 3)
        read -r cpu _ < <(bench_stats "$tsv" "$label" 7)
        rss=$(awk -F'\t' -v l="$label" '$1 == l && $6 > m { m = $6 } END { printf "%.0f", m / 1024 }' "$tsv")
        printf '| %s | %.1f | %.1f | %s | %.2f |\n' "$label" "$wall" "$cpu" "$rss" \
            "$(awk -v a="$wall" -v b="$single" 'BEGIN { print a / b }')"
    done
} | tee "$report"
