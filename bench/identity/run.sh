#!/usr/bin/env bash
# Bit-identity check (issue 28): runs two modestack binaries, OLD and NEW, over the
# same inputs with every subcommand and every denoise option, and compares what
# they write file by file. A restructuring that must not change behaviour passes
# when every case prints "same". Not a benchmark, not part of ctest.
#
#   bench/identity/run.sh OLD NEW [WORK]      (or OLD=... NEW=... IDENTITY_DIR=... bench/identity/run.sh)
#
# 1. Inputs, made once with OLD in WORK/inputs: the built-in scenes switch and
#    orbit (96x72, 16 frames, 4 spp), a tall switch (32x1024) that --max-memory
#    can make stream, flythrough and the glTF test room with --points (object
#    space), and the first CYCLES_FRAMES frames of the Cycles shots spin_room
#    and sweep_room (linked, so every command sees a whole shot).
# 2. Each case runs with OLD, then with NEW, in the same directory WORK/run and
#    through one wrapper path (WORK/bin/modestack), so the command line and the
#    paths the outputs record are the same for both; OCIO points both at this
#    repository's config for the same reason. Outputs, stdout, stderr and the
#    exit status are kept in WORK/old/CASE and WORK/new/CASE.
# 3. compare_outputs.py compares the two trees byte for byte, ignoring only
#    what the clock and the allocator decide (JSON timing and memory keys, EXR
#    date and seconds attributes, the report's timing rows); an EXR that still
#    differs is read with idiff to say whether pixels or only the header differ.
#    WORK/details/CASE.txt lists every file that differs.
# Prints one line per case, then a count; exits 0 when all are the same, 1 when
# any case differs or fails, 2 on bad usage.
#
# Environment:
#   CYCLES_DIR      the Cycles shots (default: ../shared/cycles next to the repository);
#                   their cases are skipped with a message when it is missing
#   CYCLES_FRAMES   frames of each Cycles shot to use (default 24 of 48)
#   ONLY            run only the cases whose name matches this extended regex
#   EXTRA_NEW_ARGS  options added to every denoise command of NEW only, to show that
#                   the check catches a change (e.g. EXTRA_NEW_ARGS="--sigma-radius 3")
# Needs idiff (openimageio-tools), python3, and mpirun for the MPI cases
# (skipped without it). 9 minutes on 2 cores shared with other builds (load average 7-11).
set -uo pipefail

usage() {
    sed -n '2,/^set -uo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2
    exit 2
}
[[ ${1:-} == -h || ${1:-} == --help ]] && usage
here=$(cd "$(dirname "$0")" && pwd)
repository=$(cd "$here/../.." && pwd)
old_binary=${1:-${OLD:-}}
new_binary=${2:-${NEW:-}}
work=${3:-${IDENTITY_DIR:-/tmp/modestack-identity}}
[[ -n $old_binary && -n $new_binary ]] || usage
for binary in "$old_binary" "$new_binary"; do
    [[ -x $binary && -f $binary ]] || { echo "identity: $binary is not an executable file" >&2; exit 2; }
done
old_binary=$(realpath "$old_binary")
new_binary=$(realpath "$new_binary")
cycles_dir=${CYCLES_DIR:-$repository/../shared/cycles}
cycles_frames=${CYCLES_FRAMES:-24}
only=${ONLY:-}
extra_new_args=${EXTRA_NEW_ARGS:-}
python=$(command -v python3) || { echo "identity: python3 is missing" >&2; exit 2; }
command -v idiff >/dev/null || { echo "identity: idiff is missing (openimageio-tools)" >&2; exit 2; }

mkdir -p "$work"
work=$(realpath "$work")
rm -rf "$work/inputs" "$work/old" "$work/new" "$work/run" "$work/details" "$work/bin"
mkdir -p "$work/inputs" "$work/old" "$work/new" "$work/details" "$work/bin"
# The config both binaries record, instead of each one's own installed copy.
export OCIO=$repository/share/ocio/config.ocio

# use_binary BINARY [EXTRA_DENOISE_ARGS]: points WORK/bin/modestack at BINARY. The
# wrapper runs it under its own path (exec -a), which is what modestack records.
use_binary() {
    local wrapper=$work/bin/modestack
    {
        echo '#!/usr/bin/env bash'
        echo "# Written by bench/identity/run.sh: runs $1 under one path for both binaries."
        printf 'extra=(%s)\n' "${2:-}"
        echo 'if [[ ${1:-} == denoise && ${#extra[@]} -gt 0 ]]; then set -- "$@" "${extra[@]}"; fi'
        printf 'exec -a %q %q "$@"\n' "$wrapper" "$1"
    } >"$wrapper"
    chmod +x "$wrapper"
}
ms() { "$work/bin/modestack" "$@"; }

same=0 different=0 failed=0 skipped=0
started=$SECONDS

# check NAME COMMAND...: runs COMMAND (in WORK/run) with OLD, then with NEW, and
# prints whether everything they wrote is the same.
check() {
    local name=$1 side
    shift
    [[ -n $only && ! $name =~ $only ]] && return 0
    local case_start=$SECONDS
    for side in old new; do
        if [[ $side == old ]]; then use_binary "$old_binary"; else use_binary "$new_binary" "$extra_new_args"; fi
        rm -rf "$work/run"
        mkdir -p "$work/run"
        (cd "$work/run" && "$@") >"$work/run/stdout.txt" 2>"$work/run/stderr.txt"
        echo $? >"$work/run/exit_status.txt"
        mv "$work/run" "$work/$side/$name"
    done
    local old_status new_status verdict
    old_status=$(<"$work/old/$name/exit_status.txt")
    new_status=$(<"$work/new/$name/exit_status.txt")
    if ((old_status != 0)); then
        verdict="FAILED (OLD exited $old_status: $(head -n 1 "$work/old/$name/stderr.txt"))"
        failed=$((failed + 1))
    elif ((new_status != 0)); then
        verdict="DIFFERENT (NEW exited $new_status: $(head -n 1 "$work/new/$name/stderr.txt"))"
        different=$((different + 1))
    elif verdict=$("$python" "$here/compare_outputs.py" "$work/old/$name" "$work/new/$name" \
        "$work/details/$name.txt"); then
        same=$((same + 1))
    else
        different=$((different + 1))
    fi
    printf '%-30s %s  [%ds]\n' "$name" "$verdict" $((SECONDS - case_start))
}

skip() {  # skip NAME WHY
    [[ -n $only && ! $1 =~ $only ]] && return 0
    printf '%-30s skipped: %s\n' "$1" "$2"
    skipped=$((skipped + 1))
}

# Case bodies that take more than one command. Each runs in WORK/run.

# compare exits 0/1/2 for pass/warn/fail like idiff: its status is an output.
compare_case() { ms compare "$@"; echo "compare exit status $?"; }

# --skip-existing: frames 1-8 are left from a --no-mode-filter run, so a NEW that
# rewrote them would differ.
skip_existing_case() {
    ms denoise "$switch" --layer DiffInd -q --no-mode-filter -o d/d.####.exr &&
        rm d/d.00{09,10,11,12,13,14,15,16}.exr &&
        ms denoise "$switch" --layer DiffInd -q --skip-existing -o d/d.####.exr --json d.json
}

# farm_case SEQ STATS_ROWS_1 STATS_ROWS_2 OPTION...: the five stages of README
# "Farm jobs and MPI", two tasks each (statistics take whole 64-row blocks).
farm_case() {
    local input=$1 rows_1=$2 rows_2=$3
    shift 3
    local options=("$@" -q)
    ms denoise "$input" "${options[@]}" --stage stats --rows "$rows_1" -o job/1.stats &&
        ms denoise "$input" "${options[@]}" --stage stats --rows "$rows_2" -o job/2.stats &&
        ms denoise "$input" "${options[@]}" --stage solve --stats job/1.stats job/2.stats -o job/shot.solve &&
        for task in 1 2; do
            ms denoise "$input" "${options[@]}" --stage survey --solve job/shot.solve --rows "$task/2" \
                -o "job/$task.survey" || return
        done &&
        for task in 1 2; do
            ms denoise "$input" "${options[@]}" --stage modes --solve job/shot.solve \
                --survey job/1.survey job/2.survey --rows "$task/2" -o "job/$task.modes" || return
        done &&
        for task in 1 2; do
            ms denoise "$input" "${options[@]}" --stage write --solve job/shot.solve \
                --survey job/1.survey job/2.survey --modes job/1.modes job/2.modes --frames "$task/2" \
                -o den/d.####.exr || return
        done
}

mpi_case() { mpirun --allow-run-as-root --oversubscribe --bind-to none -n 2 "$work/bin/modestack" denoise "$@"; }

# --- Inputs (OLD) -------------------------------------------------------------
use_binary "$old_binary"
inputs=$work/inputs
echo "identity: OLD $old_binary"
echo "identity: NEW $new_binary${extra_new_args:+ (denoise with extra options: $extra_new_args)}"
echo "identity: work in $work; making the inputs with OLD"
make_inputs() {
    local size=96x72 frames=1-16
    ms render --scene switch --size $size --frames $frames --spp 4 -q -o "$inputs/switch/n.####.exr" &&
        ms render --scene orbit --size $size --frames $frames --spp 4 -q -o "$inputs/orbit/n.####.exr" &&
        ms render --scene switch --size 32x1024 --frames $frames --spp 4 -q -o "$inputs/tall/n.####.exr" &&
        ms render --scene flythrough --size $size --frames $frames --spp 4 -q \
            --points "$inputs/fly/p.####.exr" -o "$inputs/fly/n.####.exr" &&
        ms render --scene "$repository/testdata/gltf/room.gltf" --size $size --frames $frames --spp 4 -q \
            --points "$inputs/room/p.####.exr" -o "$inputs/room/n.####.exr" 2>/dev/null &&
        ms denoise "$inputs/switch/n.####.exr" --layer DiffInd -q -o "$inputs/switch_denoised/d.####.exr"
}
if ! make_inputs; then
    echo "identity: OLD could not make the inputs" >&2
    exit 1
fi
switch=$inputs/switch/n.####.exr
orbit=$inputs/orbit/n.####.exr
# The streamed case: what OLD holds before planning, plus 5 MiB, is between the
# smallest streamed band and the kept shot of the tall input (measured with
# 1a39232, whose budget counts what files really hold: +3 streams in short
# bands, +4 and +5 in 16-row bands, +6 in 32-row ones, +7 keeps the shot; the
# held figure moves by about 1 MiB from run to run). Against an OLD from before
# 4479781, whose held figure counts about 3 MiB more for this input, NEW keeps
# the shot at this budget (the pixels are the same either way).
held_mib=$(ms denoise "$inputs/tall/n.####.exr" --layer DiffInd -q --max-memory 1M -o "$inputs/probe/x.####.exr" 2>&1 |
    sed -n 's/.*alone hold about \([0-9]*\) MiB.*/\1/p')
streamed_budget=$((${held_mib:-150} + 5))M
cycles_ok=0
if [[ -d $cycles_dir/spin_room/spp4 && -d $cycles_dir/sweep_room/spp4 ]]; then
    cycles_ok=1
    for shot in spin_room sweep_room; do
        for variant in spp4 ref; do
            mkdir -p "$inputs/$shot/$variant"
            for ((frame = 1; frame <= cycles_frames; frame++)); do
                printf -v file 'frame.%04d.exr' $frame
                ln -s "$(realpath "$cycles_dir/$shot/$variant/$file")" "$inputs/$shot/$variant/$file"
            done
        done
    done
    spin=$inputs/spin_room/spp4/frame.####.exr
    sweep=$inputs/sweep_room/spp4/frame.####.exr
else
    echo "identity: no Cycles shots in $cycles_dir (set CYCLES_DIR): their cases are skipped"
fi
have_mpi=0
command -v mpirun >/dev/null && have_mpi=1
echo "identity: inputs ready after $((SECONDS - started)) s; streamed budget $streamed_budget"
echo

# --- Cases --------------------------------------------------------------------
den=(denoise "$switch" --layer DiffInd -q -o d/d.####.exr)
dj=("${den[@]}" --json d.json)

check render-switch ms render --scene switch --size 96x72 --frames 1-16 -q -o r/n.####.exr --json r.json
check render-options ms render --scene orbit --size 64x48 --frames 1-4 --spp 8 --seed 9 --max-depth 3 \
    --fixed-seed -q -o r/n.####.exr --json r.json
check render-points ms render --scene flythrough --size 64x48 --frames 1-6 --point-count 2000 -q \
    --points p/p.####.exr -o r/n.####.exr --json r.json
check render-gltf ms render --scene "$repository/testdata/gltf/room.gltf" --size 64x48 --frames 1-6 --fps 30 -q \
    --points p/p.####.exr -o r/n.####.exr --json r.json
check info ms info "$switch" --json i.json --all-attributes

check denoise-default ms "${den[@]}"
check denoise-orbit ms denoise "$orbit" --layer DiffInd -q -o d/d.####.exr --json d.json
check json ms "${dj[@]}"
check rank-3 ms "${dj[@]}" --rank 3
check rank-rule-variance ms "${dj[@]}" --no-mode-filter --rank-rule variance
check rank-rule-noise-floor ms "${dj[@]}" --no-mode-filter --rank-rule noise-floor
check method-gram ms "${dj[@]}" --method gram
check method-rsvd ms "${dj[@]}" --method rsvd
check max-memory-streamed ms denoise "$inputs/tall/n.####.exr" --layer DiffInd -q -o d/d.####.exr --json d.json \
    --max-memory "$streamed_budget"
check frames-subset ms "${dj[@]}" --frames 3-14
check no-firefly-clamp ms "${dj[@]}" --no-firefly-clamp
check firefly-k-3 ms "${dj[@]}" --firefly-k 3
check sigma-radius-0 ms "${dj[@]}" --sigma-radius 0
check sigma-radius-4 ms "${dj[@]}" --sigma-radius 4
check no-mode-filter ms "${dj[@]}" --no-mode-filter
check mode-filter-modes-8 ms "${dj[@]}" --mode-filter-modes 8
check mode-filter-widths ms "${dj[@]}" --mode-filter-widths 1,2.5
check mode-filter-guides-none ms "${dj[@]}" --mode-filter-guides none
check mode-filter-guides-list ms "${dj[@]}" --mode-filter-guides albedo,normal
check rank-map ms "${dj[@]}" --rank-map map/rank.####.exr
check save-modes ms "${dj[@]}" --save-modes modes
check report ms "${dj[@]}" --report report.html
check transform-log ms "${dj[@]}" --transform log
check transform-log-0.5 ms "${dj[@]}" --transform log:0.5
check transform-pow-2 ms "${dj[@]}" --transform pow:2
check non-negative ms "${dj[@]}" --no-mode-filter --rank 8 --non-negative
check non-negative-keep-sum ms "${dj[@]}" --no-mode-filter --rank 8 --non-negative --non-negative-mode keep-sum
check shrink-optimal ms "${dj[@]}" --no-mode-filter --rank 8 --shrink optimal
check segments-auto ms "${dj[@]}" --segments auto
check segments-list ms "${dj[@]}" --segments 1-8,9-16
check train-frames ms "${dj[@]}" --no-mode-filter --train-frames 1-16x2
check weight-smoothing ms "${dj[@]}" --weight-smoothing
check no-weight-smoothing ms "${dj[@]}" --no-weight-smoothing
check whiten-on ms "${dj[@]}" --whiten on
check whiten-off ms "${dj[@]}" --whiten off
check threads-1 ms "${dj[@]}" --threads 1
check threads-2 ms "${dj[@]}" --threads 2
check skip-existing skip_existing_case
check colorspace-srgb ms "${dj[@]}" --colorspace sRGB
check ocio-config ms "${dj[@]}" --ocio-config "$OCIO"
check layers-two ms "${dj[@]}" --layer Combined
# The codec is an option since issue 28 (it was MODESTACK_EXR_READER/WRITER=openimageio
# before): against an older binary these two cases fail on OLD's side.
check exr-codec-openimageio ms "${dj[@]}" --exr-codec openimageio

check object-space-fly ms denoise "$inputs/fly/n.####.exr" --layer DiffInd --object-space "$inputs/fly/p.####.exr" \
    -q -o d/d.####.exr --json d.json
check object-space-fly-no-filter ms denoise "$inputs/fly/n.####.exr" --layer DiffInd --no-mode-filter \
    --object-space "$inputs/fly/p.####.exr" -q -o d/d.####.exr --json d.json
check object-space-gltf ms denoise "$inputs/room/n.####.exr" --layer DiffInd \
    --object-space "$inputs/room/p.####.exr" -q -o d/d.####.exr --json d.json

check farm farm_case "$switch" 0-63 64-71 --layer DiffInd
if ((have_mpi)); then
    check mpi mpi_case "$switch" --layer DiffInd -q -o d/d.####.exr --json d.json
else
    skip mpi "no mpirun"
fi

check refine ms refine --scene switch --denoised "$inputs/switch_denoised/d.####.exr" --size 96x72 --spp 16 -q \
    -o r/r.####.exr --masks m/m.####.exr --json r.json
check refine-budget ms refine --scene switch --denoised "$inputs/switch_denoised/d.####.exr" --size 96x72 \
    --spp 16 --frames 4-9 --budget 5 --dilate 2 --feather 1 -q -o r/r.####.exr --json r.json
check compare compare_case "$inputs/switch_denoised/d.####.exr" "$switch" --layer DiffInd -q --json c.json
check run ms run --scene switch --size 64x48 --frames 1-8 --refine-spp 16 --reference-spp 16 -q -o out

if ((cycles_ok)); then
    check cycles-spin ms denoise "$spin" --layer DiffInd -q -o d/d.####.exr
    # Two layers: a binary from before 2026-12-04's layers apart shares their modes (today's --joint),
    # so these two cases differ between such a binary and a later one by design.
    check cycles-spin-two-layers ms denoise "$spin" --layer DiffInd --layer DiffDir -q -o d/d.####.exr --json d.json
    check cycles-sweep-two-layers ms denoise "$sweep" --layer DiffInd --layer DiffDir -q -o d/d.####.exr \
        --json d.json
    check cycles-spin-farm farm_case "$spin" 0-63 64-119 --layer DiffInd
    if ((have_mpi)); then
        check cycles-spin-mpi mpi_case "$spin" --layer DiffInd -q -o d/d.####.exr --json d.json
    else
        skip cycles-spin-mpi "no mpirun"
    fi
    check cycles-compare compare_case "$spin" "$inputs/spin_room/ref/frame.####.exr" --layer DiffInd \
        --layer DiffDir -q --json c.json
else
    for name in cycles-spin cycles-spin-two-layers cycles-sweep-two-layers cycles-spin-farm cycles-spin-mpi \
        cycles-compare; do
        skip "$name" "no Cycles shots in $cycles_dir"
    done
fi

echo
echo "identity: $same same, $different different, $failed failed, $skipped skipped in $((SECONDS - started)) s" \
    "(details: $work/details)"
((different == 0 && failed == 0))
