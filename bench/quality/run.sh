#!/usr/bin/env bash
# Quality benchmark of `modestack denoise` (issue 7). Not a test: it never fails on quality.
#
# For each built-in scene (static, orbit, switch, spin, sweep, cross) at SIZE (160x120), FRAMES (48)
# frames:
#  1. renders a reference at REF_SPP (256) with seed REF_SEED (7) and noisy renders at
#     FIT_SPP (1 2 4 8 16) with seed 1 (renders are kept in QUALITY_DIR and reused when
#     their JSON says they were made with the same settings);
#  2. for each input spp M in INPUT_SPP (1 4 16): the noisy input, a sliding temporal mean of
#     5 frames, a per-frame Gaussian blur of 1.5 px (both written by quality.py), `modestack
#     denoise --layer DiffInd` with the automatic rank and with every fixed rank in
#     RANKS (1..8) to find the best N; every result is scored by `modestack compare` against
#     the reference;
#  3. the Cycles shot /work/shared/cycles/spin_room (4 spp against its 512-spp reference)
#     the same way (no spp sweep there: c comes from the 4-spp input alone);
#  4. failure cases: orbit rendered with --fixed-seed at 4 spp, the transient box of switch
#     (frames 30-36) and `modestack refine` on the denoised switch shot; fast light (issue 29):
#     sweep (hard shadows that move every frame) and cross (a box and its shadow in frames
#     20-27 only) scored on DiffDir too, per frame: noisy, Gaussian 1.5 px, default denoise,
#     with DiffDir's own c/s fit so the reference's noise b is counted as for DiffInd;
#  5. quality.py fits relMSE(s) = c/s, the time model t(s) = t0 + k*s, and quality_report.py
#     writes RESULTS_DIR/quality.md (+ quality_summary.md, quality.json) and the plots
#     RESULTS_DIR/quality_{relmse_vs_spp,spectra,error_maps,transient_per_frame}.png.
# The formulas are the ones of docs/design.md, "How quality is measured".
#
# Environment: QUALITY_DIR (work files, default /tmp/modestack-quality), BUILD_DIR (default
# $QUALITY_DIR/build; set it to an existing Release build to skip building), SIZE, FRAMES,
# REF_SPP, REF_SEED, FIT_SPP, INPUT_SPP, RANKS, SCENES, CYCLES_DIR (default
# /work/shared/cycles/spin_room; skipped when absent), RESULTS_DIR (default bench/results: a trial
# run at a small SIZE should write elsewhere), STAGE=render to only render.
# Takes ~20-30 min on 2 idle cores for the first 4 scenes (the references are ~2/3 of it; ~50 min
# on the busy shared machine of 2026-11-23), sweep and cross add ~26 min (busy machine,
# 2026-12-04); a re-run reuses renders, denoised outputs and comparisons (~1 min).
# Needs /usr/bin/python3 with Debian's python3-numpy, python3-openimageio, python3-matplotlib.
set -euo pipefail
cd "$(dirname "$0")/../.."
repository=$PWD

quality_dir=${QUALITY_DIR:-/tmp/modestack-quality}
build_dir=${BUILD_DIR:-$quality_dir/build}
size=${SIZE:-160x120}
frames=${FRAMES:-48}
ref_spp=${REF_SPP:-256}
ref_seed=${REF_SEED:-7}
fit_spp=${FIT_SPP:-1 2 4 8 16}
input_spp=${INPUT_SPP:-1 4 16}
ranks=${RANKS:-1 2 3 4 5 6 7 8}
cycles_dir=${CYCLES_DIR:-/work/shared/cycles/spin_room}
scenes=${SCENES:-static orbit switch spin sweep cross}
python=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1  # no __pycache__ in the source tree
results=${RESULTS_DIR:-$repository/bench/results}
mkdir -p "$quality_dir" "$results"

# The fit, the filters and the plots need Debian's numpy, OpenImageIO and matplotlib for
# /usr/bin/python3 (a pyenv python3 on PATH would not have them).
missing=()
for module_package in numpy:python3-numpy OpenImageIO:python3-openimageio matplotlib:python3-matplotlib; do
    "$python" -c "import ${module_package%%:*}" 2>/dev/null || missing+=("${module_package#*:}")
done
if ((${#missing[@]})); then
    echo "quality: $python lacks ${missing[*]}; install them with:" >&2
    echo "    apt-get install -y ${missing[*]}" >&2
    exit 1
fi

if [[ ! -x $build_dir/app/modestack ]]; then
    cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMODESTACK_BUILD_TESTS=OFF >/dev/null
    cmake --build "$build_dir" --target modestack >/dev/null
fi
modestack=$build_dir/app/modestack
quality_py=$repository/bench/quality/quality.py
echo "quality: $($modestack --version), work files in $quality_dir" >&2

# render_once SCENE DIR SPP SEED [--fixed-seed]: DIR/f.####.exr and DIR.json, unless DIR.json
# already records the same scene, size, frames, spp, seed and seed mode.
render_once()
{
    local scene=$1 directory=$2 spp=$3 seed=$4 fixed=${5:-}
    local want="$scene $size 1-$frames $spp $seed $([[ -n $fixed ]] && echo true || echo false)"
    if [[ -f $directory.json ]] &&
        [[ $("$python" "$quality_py" render-key "$directory.json") == "$want" ]]; then
        return
    fi
    rm -rf "$directory" "$directory.json"
    echo "quality: render $scene $spp spp seed $seed $fixed" >&2
    "$modestack" render --scene "$scene" --size "$size" --frames "1-$frames" --spp "$spp" \
        --seed "$seed" $fixed -o "$directory/f.####.exr" --json "$directory.json.tmp" -q
    mv "$directory.json.tmp" "$directory.json"
}

# The noisy renders first (cheap), then the references, so an interrupted run keeps the most.
for scene in $scenes; do
    for spp in $fit_spp $input_spp; do
        render_once "$scene" "$quality_dir/$scene/noisy_s$spp" "$spp" 1
    done
done
if [[ " $scenes " == *" orbit "* ]]; then
    render_once orbit "$quality_dir/orbit/fixed_s4" 4 1 --fixed-seed
fi
for scene in $scenes; do
    render_once "$scene" "$quality_dir/$scene/ref" "$ref_spp" "$ref_seed"
done
[[ ${STAGE:-} == render ]] && exit 0

# up_to_date OUTPUT SEQ...: OUTPUT exists and is newer than the first frame of every SEQ.
up_to_date()
{
    local output=$1 sequence
    shift
    [[ -f $output ]] || return 1
    for sequence in "$@"; do
        local frames_on_disk=("$(dirname "$sequence")"/*.exr)
        [[ $output -nt ${frames_on_disk[0]} ]] || return 1
    done
}

# The layer compare, denoise and baseline work on; the DiffDir evaluation sets it locally.
layer=DiffInd

# compare TEST REF JSON [OPTIONS]: `modestack compare` on $layer into JSON (kept when it exists
# and is newer than TEST's first frame). Its exit code 1/2 (warn/fail against idiff's tiny
# default thresholds) is expected; 3 and above are errors.
compare()
{
    local test=$1 reference=$2 output=$3
    shift 3
    if up_to_date "$output" "$test" "$reference"; then
        return
    fi
    local status=0
    "$modestack" compare "$test" "$reference" --layer "$layer" --json "$output.tmp" -q "$@" >/dev/null || status=$?
    if ((status > 2)); then
        echo "quality: compare $test $reference failed with exit code $status" >&2
        return 1
    fi
    mv "$output.tmp" "$output"
}

# denoise INPUT DIR [OPTIONS]: DIR/f.####.exr and DIR.json (reused when DIR.json exists and is
# newer than the input's first frame).
denoise()
{
    local input=$1 directory=$2
    shift 2
    if up_to_date "$directory.json" "$input"; then
        return
    fi
    rm -rf "$directory"
    "$modestack" denoise "$input" --layer "$layer" -o "$directory/f.####.exr" --json "$directory.json.tmp" -q "$@"
    mv "$directory.json.tmp" "$directory.json"
}

# baseline KIND INPUT DIR: the temporal-mean or Gaussian baseline, DIR/f.####.exr and DIR.json.
baseline()
{
    local kind=$1 input=$2 directory=$3
    if up_to_date "$directory.json" "$input"; then
        return
    fi
    rm -rf "$directory"
    "$python" "$quality_py" baseline "$kind" "$input" "$directory" --json "$directory.json" --layer "$layer"
}

# evaluate INPUT REF DIR: every method on one noisy input; results in DIR/*.json.
evaluate()
{
    local input=$1 reference=$2 directory=$3 rank
    mkdir -p "$directory"
    echo "quality: evaluate $directory" >&2
    compare "$input" "$reference" "$directory/noisy.cmp.json"
    baseline temporal "$input" "$directory/temporal"
    compare "$directory/temporal/f.####.exr" "$reference" "$directory/temporal.cmp.json"
    baseline gaussian "$input" "$directory/gaussian"
    compare "$directory/gaussian/f.####.exr" "$reference" "$directory/gaussian.cmp.json"
    rm -rf "$directory/temporal"
    # sweep's and cross's 4-spp Gaussian stays for the report's box region (failure case 3).
    [[ $directory == */sweep/s4 || $directory == */cross/s4 ]] || rm -rf "$directory/gaussian"
    denoise "$input" "$directory/auto"
    compare "$directory/auto/f.####.exr" "$reference" "$directory/auto.cmp.json"
    for rank in $ranks; do
        denoise "$input" "$directory/rank_$rank" --rank "$rank"
        compare "$directory/rank_$rank/f.####.exr" "$reference" "$directory/rank_$rank.cmp.json"
        rm -rf "$directory/rank_$rank"
    done
}

for scene in $scenes; do
    reference=$quality_dir/$scene/ref/f.####.exr
    for spp in $fit_spp $input_spp; do
        compare "$quality_dir/$scene/noisy_s$spp/f.####.exr" "$reference" "$quality_dir/$scene/fit_s$spp.cmp.json"
    done
    for spp in $input_spp; do
        evaluate "$quality_dir/$scene/noisy_s$spp/f.####.exr" "$reference" "$quality_dir/$scene/s$spp"
    done
done

# Failure case 1: temporally correlated noise (the same random numbers in every frame).
if [[ " $scenes " == *" orbit "* ]]; then
    fixed=$quality_dir/orbit/fixed
    mkdir -p "$fixed"
    compare "$quality_dir/orbit/fixed_s4/f.####.exr" "$quality_dir/orbit/ref/f.####.exr" "$fixed/noisy.cmp.json"
    denoise "$quality_dir/orbit/fixed_s4/f.####.exr" "$fixed/auto"
    compare "$fixed/auto/f.####.exr" "$quality_dir/orbit/ref/f.####.exr" "$fixed/auto.cmp.json"
fi

# Failure case 2: transient content, the box crossing the floor of switch in frames 30-36, at
# 4 spp: noisy, denoised (auto and best rank are compared in the report) and refined.
if [[ " $scenes " == *" switch "* && " $input_spp " == *" 4 "* ]]; then
    transient=$quality_dir/switch/transient
    mkdir -p "$transient"
    switch_reference=$quality_dir/switch/ref/f.####.exr
    compare "$quality_dir/switch/noisy_s4/f.####.exr" "$switch_reference" "$transient/noisy.cmp.json" --frames 30-36
    compare "$quality_dir/switch/s4/auto/f.####.exr" "$switch_reference" "$transient/auto.cmp.json" --frames 30-36
    best_rank=$("$python" "$quality_py" best-rank "$quality_dir/switch/s4")
    denoise "$quality_dir/switch/noisy_s4/f.####.exr" "$transient/rank_best" --rank "$best_rank"
    compare "$transient/rank_best/f.####.exr" "$switch_reference" "$transient/rank_best.cmp.json" --frames 30-36
    if "$modestack" --help | grep -q '^ *refine '; then
        if [[ ! -f $transient/refined.json || $transient/refined.json -ot $quality_dir/switch/s4/auto.json ]]; then
            rm -rf "$transient/refined"
            "$modestack" refine --scene switch --size "$size" --denoised "$quality_dir/switch/s4/auto/f.####.exr" \
                -o "$transient/refined/f.####.exr" --json "$transient/refined.json.tmp" -q
            mv "$transient/refined.json.tmp" "$transient/refined.json"
        fi
        compare "$transient/refined/f.####.exr" "$switch_reference" "$transient/refined.cmp.json" --frames 30-36
        compare "$transient/refined/f.####.exr" "$switch_reference" "$transient/refined_shot.cmp.json"
    fi
fi

# Failure case 3: fast light (issue 29). sweep and cross on their direct light, where the hard
# shadows move: the noisy renders against the reference at every spp (DiffDir's own c/s fit),
# then at each input spp the noisy input, the Gaussian and the default denoise of --layer DiffDir
# (their DiffInd rows are the evaluation above). Every compare JSON holds per-frame figures:
# the report shows the worst frame, and for cross the crossing frames 20-27 (kCrossFirstFrame..
# kCrossLastFrame of core/scene/builtin_scenes.h) and the pixels the box changes.
evaluate_direct()
{
    local scene=$1 layer=DiffDir spp
    local reference=$quality_dir/$scene/ref/f.####.exr direct=$quality_dir/$scene/direct
    mkdir -p "$direct"
    for spp in $fit_spp $input_spp; do
        compare "$quality_dir/$scene/noisy_s$spp/f.####.exr" "$reference" "$direct/fit_s$spp.cmp.json"
    done
    for spp in $input_spp; do
        local input=$quality_dir/$scene/noisy_s$spp/f.####.exr directory=$direct/s$spp
        echo "quality: evaluate $directory (DiffDir)" >&2
        mkdir -p "$directory"
        compare "$input" "$reference" "$directory/noisy.cmp.json"
        baseline gaussian "$input" "$directory/gaussian"
        compare "$directory/gaussian/f.####.exr" "$reference" "$directory/gaussian.cmp.json"
        denoise "$input" "$directory/auto"
        compare "$directory/auto/f.####.exr" "$reference" "$directory/auto.cmp.json"
        # Kept for the report's box region and error maps: the 4-spp results only.
        [[ $spp == 4 ]] || rm -rf "$directory/gaussian" "$directory/auto"
    done
}
for scene in sweep cross; do
    if [[ " $scenes " == *" $scene "* ]]; then
        evaluate_direct "$scene"
    fi
done

# The Cycles shot: 4 spp against its 512-spp reference, no spp sweep.
if [[ -d $cycles_dir/spp4 && -d $cycles_dir/ref ]]; then
    mkdir -p "$quality_dir/spin_room"
    compare "$cycles_dir/spp4/frame.####.exr" "$cycles_dir/ref/frame.####.exr" "$quality_dir/spin_room/fit_s4.cmp.json"
    evaluate "$cycles_dir/spp4/frame.####.exr" "$cycles_dir/ref/frame.####.exr" "$quality_dir/spin_room/s4"
fi

"$python" "$quality_py" report "$quality_dir" "$results" --scenes "$scenes" --fit-spp "$fit_spp" \
    --input-spp "$input_spp" --ref-spp "$ref_spp" --ref-seed "$ref_seed" --size "$size" --frames "$frames" \
    --cycles-dir "$cycles_dir" --machine "$(nproc) cores ($(lscpu | sed -n 's/^Model name: *//p' | head -n 1)), load average $(cut -d' ' -f1-3 /proc/loadavg)" \
    --command "bench/quality/run.sh"
echo "quality: wrote $results/quality.md and $results/quality_*.png" >&2
