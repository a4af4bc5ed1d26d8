#!/usr/bin/env bash
# Benchmark of `modestack denoise` (issue 4). Not a test: it never fails on time.
#
# 1. Builds modestack and the bench tools (Release, -DMODESTACK_BUILD_BENCH=ON).
# 2. Makes a 1920x1080 RGB half-float ZIP sequence of 100 noisy frames with
#    bench_make_noisy_sequence (low-rank signal + noise, see its header) in
#    $BENCH_DIR (default /tmp/modestack-bench); kept between runs.
# 3. Times the I/O floor (bench_io_floor: read all channels, write them back
#    with 3 extra half channels, ZIP, frames in parallel), once with noise-like
#    extra channels and once writing exactly the pixels of our gram output
#    (ZIP's speed depends on the data; the second is the fair floor), the
#    latter also through modestack's own I/O (bench_io_floor_modestack), and
#    `modestack denoise --method gram|rsvd`, each with the default --max-memory
#    and with --max-memory $STREAMED_MEMORY (default 512M; a run the budget
#    refuses gets a row saying so, with modestack's message), and gram with
#    --no-mode-filter, REPEATS times
#    each (default 3): wall time, CPU time, peak RSS (GNU time), phase times and
#    passes from --json.
# 4. Times gram against rsvd on a small 320x240 image with 48, 200 and 800
#    frames, to place `--method auto`'s switch.
# Prints Markdown tables (also in $BENCH_DIR/results/denoise.md); raw runs in
# $BENCH_DIR/results/*.tsv and the JSON summaries next to them.
#
# Environment: BENCH_DIR, BUILD_DIR (default $BENCH_DIR/build), REPEATS,
# SMALL_REPEATS (default REPEATS), FRAMES (100), SIZE (1920x1080), SMALL_FRAMES ("48 200 800"), SMALL_SIZE
# (320x240), SKIP_LARGE=1 or SKIP_SMALL=1 to run one half only, METHODS ("gram rsvd"; gram
# always runs: the floor of our bytes is its output).
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/common.sh

bench_dir=${BENCH_DIR:-/tmp/modestack-bench}
build_dir=${BUILD_DIR:-$bench_dir/build}
repeats=${REPEATS:-3}
small_repeats=${SMALL_REPEATS:-$repeats}
frames=${FRAMES:-100}
size=${SIZE:-1920x1080}
small_frames=${SMALL_FRAMES:-48 200 800}
small_size=${SMALL_SIZE:-320x240}
methods=${METHODS:-gram rsvd}
streamed=${STREAMED_MEMORY:-512M}
results=$bench_dir/results
mkdir -p "$bench_dir" "$results"

scripts/install-deps
bench_require_packages time jq
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMODESTACK_BUILD_TESTS=OFF \
    -DMODESTACK_BUILD_BENCH=ON >/dev/null
cmake --build "$build_dir" --target modestack bench_make_noisy_sequence bench_io_floor bench_io_floor_modestack \
    >/dev/null
modestack=$build_dir/app/modestack
make_sequence=$build_dir/bench/bench_make_noisy_sequence
io_floor=$build_dir/bench/bench_io_floor
io_floor_modestack=$build_dir/bench/bench_io_floor_modestack

# make_data DIR SIZE FRAMES: the noisy sequence DIR/noisy.%04d.exr, made once.
make_data()
{
    local directory=$1 data_size=$2 data_frames=$3 stamp="$1/made-with"
    local description="$data_size $data_frames seed 1 noise 0.35"
    if [[ -f $stamp && $(cat "$stamp") == "$description" ]]; then
        return
    fi
    rm -rf "$directory"
    mkdir -p "$directory"
    echo "bench: making $data_frames noisy frames of $data_size in $directory" >&2
    "$make_sequence" --size "$data_size" --frames "$data_frames" --seed 1 --noise 0.35 \
        -o "$directory/noisy.%04d.exr" >/dev/null
    echo "$description" >"$stamp"
}

# denoise_run TSV LABEL RUN DATA_DIR ARGS...: one timed denoise into
# $bench_dir/out (left there for the content floor); keeps its JSON.
denoise_run()
{
    local tsv=$1 label=$2 run=$3 data=$4
    shift 4
    rm -rf "$bench_dir/out"
    bench_time "$tsv" "$label" "$run" "$modestack" denoise "$data/noisy.%04d.exr" \
        -o "$bench_dir/out/denoised.%04d.exr" --json "$results/$label.$run.json" -q "$@"
}

# floor_run TSV RUN DATA_DIR [CONTENT_PATTERN]: one timed I/O floor. The noisy
# floor is timed by GNU time like the rest; the content floor by its own clock,
# which starts after the content frames are loaded (CPU columns: not measured).
floor_run()
{
    local tsv=$1 run=$2 data=$3 content=${4:-}
    local floor=$bench_dir/floor
    rm -rf "$floor"
    mkdir -p "$floor"
    if [[ -z $content ]]; then
        bench_time "$tsv" io-floor "$run" "$io_floor" "$data/noisy.%04d.exr" "$floor/floor.%04d.exr" 1 "$frames" \
            >/dev/null
        floor_bytes=$(du -sb "$floor" | cut -f1)
    else
        local seconds
        seconds=$("$io_floor" "$data/noisy.%04d.exr" "$floor/floor.%04d.exr" 1 "$frames" 64 3 "$content" |
            jq -r .seconds)
        printf '%s\t%s\t%s\t%s\t%s\t%s\n' io-floor-content "$run" "$seconds" nan nan 0 >>"$tsv"
        echo "bench: io-floor-content run $run: $seconds s wall (own clock)" >&2
        content_bytes=$(du -sb "$floor" | cut -f1)
        # The same bytes through modestack's own reader and writer (libdeflate for ZIP).
        rm -rf "$floor"
        mkdir -p "$floor"
        seconds=$("$io_floor_modestack" "$data/noisy.%04d.exr" "$floor/floor.%04d.exr" 1 "$frames" 64 "$content" |
            jq -r .seconds)
        printf '%s\t%s\t%s\t%s\t%s\t%s\n' io-floor-modestack "$run" "$seconds" nan nan 0 >>"$tsv"
        echo "bench: io-floor-modestack run $run: $seconds s wall (own clock)" >&2
    fi
    rm -rf "$floor"
}

# streamed_run TSV METHOD RUN DATA_DIR: denoise_run at --max-memory $streamed; a
# refusal (the budget too small for the shot) is kept in $results/METHOD-$streamed.refused.
streamed_run()
{
    local tsv=$1 method=$2 run=$3 data=$4 refusal=$results/$2-$streamed.refused
    rm -f "$refusal"
    if ! denoise_run "$tsv" "$method-$streamed" "$run" "$data" --method "$method" --max-memory "$streamed" \
        2>"$refusal.log"; then
        grep '^modestack: ' "$refusal.log" >"$refusal" || cp "$refusal.log" "$refusal"
        echo "bench: $method at --max-memory $streamed refused: $(cat "$refusal")" >&2
    fi
    grep '^bench: ' "$refusal.log" >&2 || true
    rm -f "$refusal.log"
}

# json_median LABEL JQ_EXPRESSION: median over the runs' JSON summaries.
json_median()
{
    local values=() file
    for file in "$results/$1".*.json; do
        values+=("$(jq -r "$2" "$file")")
    done
    bench_median_of "${values[@]}"
}

report=$results/denoise.md
{
    echo "### modestack denoise benchmark"
    echo
    echo "Machine: $(bench_machine)."
    echo "Source: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' + uncommitted changes')."
    echo "Each figure: min / median of $repeats runs (shared machine: the min is the best estimate)."
    echo "Inputs stay in the page cache (warm reads); outputs are written to the page cache, not synced."
} >"$report"

if [[ ${SKIP_LARGE:-0} != 1 ]]; then
    data=$bench_dir/noisy-$size-$frames
    make_data "$data" "$size" "$frames"
    tsv=$results/denoise-large.tsv
    : >"$tsv"
    rm -f "$results"/gram-*.json "$results"/rsvd-*.json
    floor_bytes=0
    content_bytes=0
    labels=()
    for method in $methods; do
        labels+=("$method-default" "$method-$streamed")
        [[ $method == gram ]] && labels+=(gram-no-filter)
    done
    for run in $(seq 1 "$repeats"); do
        denoise_run "$tsv" gram-default "$run" "$data" --method gram
        floor_run "$tsv" "$run" "$data"
        floor_run "$tsv" "$run" "$data" "$bench_dir/out/denoised.%04d.exr"
        streamed_run "$tsv" gram "$run" "$data"
        denoise_run "$tsv" gram-no-filter "$run" "$data" --method gram --no-mode-filter
        if [[ " $methods " == *" rsvd "* ]]; then
            denoise_run "$tsv" rsvd-default "$run" "$data" --method rsvd
            streamed_run "$tsv" rsvd "$run" "$data"
        fi
    done
    rm -rf "$bench_dir/out"
    read -r floor_min floor_median < <(bench_stats "$tsv" io-floor 3)
    read -r floor_cpu_min floor_cpu_median < <(bench_stats "$tsv" io-floor 7)
    read -r content_min content_median < <(bench_stats "$tsv" io-floor-content 3)
    read -r own_min own_median < <(bench_stats "$tsv" io-floor-modestack 3)
    read -r width height < <(echo "$size" | tr x ' ')
    input_bytes=$(du -sb "$data" | cut -f1)
    ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
    {
        echo
        echo "Data: $frames frames of ${width}x${height} RGB half ZIP ($((input_bytes >> 20)) MiB in)."
        echo "I/O floor, noisy: reads every frame, writes R,G,B + 3 half channels of noise-like data ($((floor_bytes >> 20)) MiB)."
        echo "I/O floor, our bytes: reads every frame, writes the pixels of our gram output ($((content_bytes >> 20)) MiB, loaded before its clock starts)."
        echo "I/O floor, our bytes, modestack's I/O: the same through io::SequenceReader and io::FrameOutput (libdeflate for ZIP), not OpenImageIO."
        echo
        echo "| run | wall s (min / med) | × floor, our bytes (min / med) | × floor, noisy (min / med) | CPU s (min / med) | CPU × noisy floor (med) | peak RSS MB (max of runs) | passes | band rows | statistics s | solve s | rebuild s | GMAC/s in statistics |"
        echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        printf '| I/O floor, our bytes | %.1f / %.1f | 1.00 / 1.00 | %s / %s | – | – | – | 1 | 64 | | | | |\n' \
            "$content_min" "$content_median" "$(ratio "$content_min" "$floor_min")" "$(ratio "$content_median" "$floor_median")"
        printf '| I/O floor, our bytes, modestack I/O | %.1f / %.1f | %s / %s | %s / %s | – | – | – | 1 | 64 | | | | |\n' \
            "$own_min" "$own_median" "$(ratio "$own_min" "$content_min")" "$(ratio "$own_median" "$content_median")" \
            "$(ratio "$own_min" "$floor_min")" "$(ratio "$own_median" "$floor_median")"
        printf '| I/O floor, noisy | %.1f / %.1f | %s / %s | 1.00 / 1.00 | %.1f / %.1f | 1.00 | %s | 1 | 64 | | | | |\n' \
            "$floor_min" "$floor_median" "$(ratio "$floor_min" "$content_min")" "$(ratio "$floor_median" "$content_median")" \
            "$floor_cpu_min" "$floor_cpu_median" \
            "$(awk -F'\t' '$1 == "io-floor" && $6 > m { m = $6 } END { printf "%.0f", m / 1024 }' "$tsv")"
        samples=$((width * height * 3))
        for label in "${labels[@]}"; do
            if [[ -f $results/$label.refused ]]; then
                printf '| %s | refused: %s | | | | | | | | | | | |\n' "$label" "$(cat "$results/$label.refused")"
                continue
            fi
            read -r wall_min wall_median < <(bench_stats "$tsv" "$label" 3)
            read -r cpu_min cpu_median < <(bench_stats "$tsv" "$label" 7)
            rss_max=$(awk -F'\t' -v l="$label" '$1 == l && $6 > m { m = $6 } END { printf "%.0f", m / 1024 }' "$tsv")
            statistics=$(json_median "$label" '.seconds.statistics')
            solve=$(json_median "$label" '.seconds.solve')
            rebuild=$(json_median "$label" '.seconds.rebuild')
            passes=$(json_median "$label" '.passes')
            band_rows=$(json_median "$label" '.band_rows')
            # Multiply-adds: Gram P·F² (the brief's count; rankUpdate does the lower
            # half, P·F²/2); rSVD per pass 2·P·F·k with k = 24 modes + 10 oversampling
            # columns, over power iterations + 2 = 4 passes (Settings defaults).
            if [[ $label == gram-* ]]; then
                macs=$(awk -v p="$samples" -v f="$frames" 'BEGIN { print p * f * f }')
            else
                macs=$(awk -v p="$samples" -v f="$frames" 'BEGIN { k = (f < 34) ? f : 34; print 4 * 2 * p * f * k }')
            fi
            printf '| %s | %.1f / %.1f | %s / %s | %s / %s | %.1f / %.1f | %s | %s | %s | %s | %.1f | %.2f | %.1f | %.2f |\n' \
                "$label" "$wall_min" "$wall_median" \
                "$(ratio "$wall_min" "$content_min")" "$(ratio "$wall_median" "$content_median")" \
                "$(ratio "$wall_min" "$floor_min")" "$(ratio "$wall_median" "$floor_median")" \
                "$cpu_min" "$cpu_median" "$(ratio "$cpu_median" "$floor_cpu_median")" \
                "$rss_max" "$passes" "$band_rows" "$statistics" "$solve" "$rebuild" \
                "$(awk -v m="$macs" -v s="$statistics" 'BEGIN { printf "%.2f", m / s / 1e9 }')"
        done
        echo
        echo "GMAC/s counts the solver's multiply-adds over the whole statistics phase (which also reads and cleans"
        echo "the frames), so it is a lower bound on the kernel's rate; 1 MAC = 2 FLOP."
    } >>"$report"
fi

if [[ ${SKIP_SMALL:-0} != 1 ]]; then
    tsv=$results/denoise-small.tsv
    : >"$tsv"
    {
        echo
        echo "Where each solver wins: ${small_size}, --rank auto (press rule), default memory; min / median of $small_repeats runs."
        echo
        echo "| frames | gram wall s (min / med) | rsvd wall s (min / med) | gram statistics + solve s | rsvd statistics + solve s | gram N | rsvd N | faster |"
        echo "|---|---|---|---|---|---|---|---|"
    } >>"$report"
    for count in $small_frames; do
        data=$bench_dir/noisy-$small_size-$count
        make_data "$data" "$small_size" "$count"
        rm -f "$results"/small-*-"$count".*.json
        for run in $(seq 1 "$small_repeats"); do
            for method in gram rsvd; do
                denoise_run "$tsv" "small-$method-$count" "$run" "$data" --method "$method"
            done
        done
        read -r gram_min gram_median < <(bench_stats "$tsv" "small-gram-$count" 3)
        read -r rsvd_min rsvd_median < <(bench_stats "$tsv" "small-rsvd-$count" 3)
        gram_math=$(json_median "small-gram-$count" '.seconds.statistics + .seconds.solve')
        rsvd_math=$(json_median "small-rsvd-$count" '.seconds.statistics + .seconds.solve')
        faster=$(awk -v g="$gram_min" -v r="$rsvd_min" 'BEGIN { print (g <= r) ? "gram" : "rsvd" }')
        printf '| %s | %.2f / %.2f | %.2f / %.2f | %.2f | %.2f | %s | %s | %s |\n' "$count" "$gram_min" "$gram_median" \
            "$rsvd_min" "$rsvd_median" "$gram_math" "$rsvd_math" \
            "$(json_median "small-gram-$count" '.rank.n')" "$(json_median "small-rsvd-$count" '.rank.n')" \
            "$faster" >>"$report"
    done
    rm -rf "$bench_dir/out"
fi

cat "$report"
