#!/usr/bin/env bash
# The estimator choice (issue 29) on every built-in scene, the two Cycles shots
# too: DiffDir and DiffInd denoised with the default and with each --estimators
# set given, scored by scenes.py against a reference made of two renders with
# other seeds (their difference counts the reference's own noise). Not a test.
#
#   bench/estimators/scenes.sh MODESTACK [WORK]
# Environment: SIZE (128x96), FRAMES (1-48), SPP (4), REF_SPP (256 per seed; two
# seeds), SCENES (static orbit switch spin sweep cross flythrough: the last one's
# camera moves), FIXED_SCENES (orbit:
# rendered again with --fixed-seed, noise that repeats, scored against the
# same references; each must be in SCENES), CYCLES_DIR
# (../shared/cycles; skipped when absent), ORBIT_CROSS_DIR (the OUTDIR of
# bench/cycles/render.sh: a Cycles shot with an orbiting light, a crossing sphere
# and a light switched on; WORK/orbit_cross_room/render; skipped unless its three
# variants are complete; its noisy_fixed too when rendered), PAN_DIR (the OUTDIR
# of SHOT=pan_room bench/cycles/render.sh: a camera pan over a glossy floor and
# a metal sphere, GlossInd scored too; WORK/pan_room/render; skipped unless
# complete), CHOICES (the --estimators lists scored beside the
# default; "rebuild,input,spatial").
# Renders are kept in WORK and reused. ~35 min of CPU for the references at
# 128x96 on the 2-core machine of 2026-12-04.
# Needs /usr/bin/python3 with Debian's python3-numpy and python3-openimageio.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
modestack=${1:?usage: scenes.sh MODESTACK [WORK]}
work=${2:-/tmp/modestack-estimator-scenes}
size=${SIZE:-128x96}
frames=${FRAMES:-1-48}
spp=${SPP:-4}
ref_spp=${REF_SPP:-256}
scenes=${SCENES:-static orbit switch spin sweep cross flythrough}
fixed_scenes=${FIXED_SCENES:-orbit}
cycles=${CYCLES_DIR:-$here/../../../shared/cycles}
orbit_cross=${ORBIT_CROSS_DIR:-$work/orbit_cross_room/render}
pan=${PAN_DIR:-$work/pan_room/render}
choices=${CHOICES:-rebuild,input,spatial}
mkdir -p "$work"

# render NAME SPP SEED SCENE [OPTIONS]: WORK/SCENE/NAME/f.####.exr, reused when complete.
render()
{
    local name=$1 samples=$2 seed=$3 scene=$4
    shift 4
    local directory=$work/$scene/$name
    [ -f "$directory/done" ] && return
    "$modestack" render --scene "$scene" --size "$size" --frames "$frames" --spp "$samples" --seed "$seed" \
        -o "$directory/f.####.exr" -q "$@"
    touch "$directory/done"
}

# denoise INPUT DIR LAYER [OPTIONS]: DIR/f.####.exr and DIR.json, reused when DIR.json exists.
denoise()
{
    local input=$1 directory=$2 layer=$3
    shift 3
    [ -f "$directory.json" ] && return
    mkdir -p "$directory"
    "$modestack" denoise "$input" --layer "$layer" -o "$directory/f.####.exr" --json "$directory.json.tmp" -q "$@"
    mv "$directory.json.tmp" "$directory.json"
}

# The transient frames of each shot: where content changes for a few frames.
declare -A transient=([switch]=30-36 [cross]=20-27 [sweep_room]=20-27 [orbit_cross_room]=20-29
                      [orbit_cross_room-fixed-seed]=20-29)
shots=()
for scene in $scenes; do
    render noisy "$spp" 1 "$scene"
    render ref_a "$ref_spp" 7 "$scene"
    render ref_b "$ref_spp" 8 "$scene"
    shots+=("$scene|$work/$scene/noisy/f.####.exr|$work/$scene/ref_a/f.*.exr|$work/$scene/ref_b/f.*.exr|")
done
# Noise that repeats from frame to frame: the first scene rendered again with a fixed seed.
for scene in $fixed_scenes; do
    render noisy_fixed "$spp" 1 "$scene" --fixed-seed
    shots+=("$scene-fixed-seed|$work/$scene/noisy_fixed/f.####.exr|$work/$scene/ref_a/f.*.exr|$work/$scene/ref_b/f.*.exr|")
done
for shot in sweep_room spin_room; do
    [ -d "$cycles/$shot" ] || { echo "SKIPPED: $cycles/$shot not found"; continue; }
    shots+=("$shot|$cycles/$shot/spp4/frame.####.exr|$cycles/$shot/ref/frame.*.exr||ViewLayer.")
done
if [ -f "$orbit_cross/noisy/done" ] && [ -f "$orbit_cross/ref_a/done" ] && [ -f "$orbit_cross/ref_b/done" ]; then
    shots+=("orbit_cross_room|$orbit_cross/noisy/frame.####.exr|$orbit_cross/ref_a/frame.*.exr|$orbit_cross/ref_b/frame.*.exr|ViewLayer.")
    [ -f "$orbit_cross/noisy_fixed/done" ] &&
        shots+=("orbit_cross_room-fixed-seed|$orbit_cross/noisy_fixed/frame.####.exr|$orbit_cross/ref_a/frame.*.exr|$orbit_cross/ref_b/frame.*.exr|ViewLayer.")
else
    echo "SKIPPED: $orbit_cross has no complete noisy, ref_a, ref_b (render them with bench/cycles/render.sh)"
fi
if [ -f "$pan/noisy/done" ] && [ -f "$pan/ref_a/done" ] && [ -f "$pan/ref_b/done" ]; then
    shots+=("pan_room|$pan/noisy/frame.####.exr|$pan/ref_a/frame.*.exr|$pan/ref_b/frame.*.exr|ViewLayer.")
else
    echo "SKIPPED: $pan has no complete noisy, ref_a, ref_b (render them with SHOT=pan_room bench/cycles/render.sh)"
fi

for entry in "${shots[@]}"; do
    IFS='|' read -r name input ref_a ref_b prefix <<< "$entry"
    layers=(DiffDir DiffInd)
    [ "$name" = pan_room ] && layers+=(GlossInd) # the glossy floor's reflections move with the camera
    for layer in "${layers[@]}"; do
        outputs=()
        denoise "$input" "$work/$name/default-$layer" "$prefix$layer"
        outputs+=("$work/$name/default-$layer/f.*.exr")
        for choice in $choices; do
            denoise "$input" "$work/$name/$choice-$layer" "$prefix$layer" --estimators "$choice"
            outputs+=("$work/$name/$choice-$layer/f.*.exr")
        done
        echo "== $name $prefix$layer"
        /usr/bin/python3 "$here/scenes.py" "${input//####/*}" "$ref_a" "${ref_b:-none}" "$prefix$layer" \
            ${transient[$name]:+--transient ${transient[$name]}} "${outputs[@]}"
    done
done
