#!/usr/bin/env bash
# Runs the estimator-choice prototype (prototype.py, issue 29) on the two Cycles
# shots: denoises DiffDir and DiffInd with today's defaults, then scores the
# noisy input, a 1.5 px Gaussian, the rebuild and the prototype's per-pixel choice
# against the 1024/512-spp references; then the binary's own choice
# (`denoise --estimators rebuild,input,spatial`, directory `choice`) beside
# today's default (`default`). Not a test. ~4 min on 2 cores.
#
#   bench/estimators/run.sh MODESTACK [WORK]     (CYCLES_DIR: default ../shared/cycles)
# Needs /usr/bin/python3 with Debian's python3-numpy and python3-openimageio.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
modestack=${1:?usage: run.sh MODESTACK [WORK]}
work=${2:-/tmp/modestack-estimators}
cycles=${CYCLES_DIR:-$here/../../../shared/cycles}
mkdir -p "$work"
# The rebuild's kept noise h per layer: the median of (rebuild - reference)^2 / v
# on these shots (the engine has the exact per-pixel value; see prototype.py).
declare -A kept=([DiffDir]=0.1 [DiffInd]=0.008)
# Frames where content changes: sweep_room's ball exists in frames 20-27.
declare -A transient=([sweep_room]="--transient 20-27" [spin_room]="")
for shot in sweep_room spin_room; do
    for layer in DiffDir DiffInd; do
        out=$work/$shot-$layer
        [ -f "$out/frame.0048.exr" ] ||
            "$modestack" denoise "$cycles/$shot/spp4/frame.####.exr" -o "$out/frame.####.exr" --layer "$layer" \
                --json "$out.json" > "$out.log" 2>&1 || { cat "$out.log"; exit 1; }
        choice=$work/choice/$shot-$layer
        mkdir -p "$work/choice"
        [ -f "$choice/frame.0048.exr" ] ||
            "$modestack" denoise "$cycles/$shot/spp4/frame.####.exr" -o "$choice/frame.####.exr" --layer "$layer" \
                --estimators rebuild,input,spatial --json "$choice.json" > "$choice.log" 2>&1 ||
            { cat "$choice.log"; exit 1; }
        mkdir -p "$work/default" && ln -sfn "$out" "$work/default/$shot-$layer"
        echo "== $shot $layer: prototype"
        /usr/bin/python3 "$here/prototype.py" "$cycles/$shot/spp4/frame.*.exr" "$out/frame.*.exr" \
            "$cycles/$shot/ref/frame.*.exr" "ViewLayer.$layer" --kept-noise "${kept[$layer]}" ${transient[$shot]}
        echo "== $shot $layer: the binary (default, then --estimators rebuild,input,spatial)"
        /usr/bin/python3 "$here/score.py" "$cycles/$shot/spp4/frame.*.exr" "$cycles/$shot/ref/frame.*.exr" \
            "ViewLayer.$layer" "$work/default/$shot-$layer/frame.*.exr" "$choice/frame.*.exr" ${transient[$shot]}
    done
done
