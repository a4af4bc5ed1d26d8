#!/usr/bin/env bash
# Several light layers of one shot denoised in one run, each on its own modes
# (`denoise --layer A --layer B ...`), against one run per layer chained (each
# run reads the last one's output, the way one file with every layer denoised
# was made before) and against --joint (one shared set of modes). Reports wall
# and CPU time and peak memory (min of RUNS repeats), checks that the one run
# gives the chained runs' bits, and scores every layer against the shot's
# high-spp reference with `modestack compare`. Not a test.
#
#   bench/layers/run.sh MODESTACK [WORK]
# Environment: CYCLES_DIR (../shared/cycles: sweep_room and spin_room, 4 spp
# against 512 spp), RUNS (2), SYNTHETIC (1280x720: a 48-frame shot of four
# synthetic layers for timing only; empty: none), LAYERS (DiffDir DiffInd
# GlossDir GlossInd).
# Writes WORK/times.tsv and WORK/summary.md.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
read -r -a layers <<<"${LAYERS:-DiffDir DiffInd GlossDir GlossInd}"

# run.sh --chained MODESTACK INPUT DIR: one run per layer, each reading the
# previous run's output; the last is DIR/last/ (a command of its own, for timing).
if [ "${1:-}" = --chained ]; then
    modestack=$2 previous=$3 directory=$4 step=0
    rm -rf "$directory"
    for layer in "${layers[@]}"; do
        step=$((step + 1))
        "$modestack" denoise "$previous" --layer "$layer" -o "$directory/$step/f.####.exr" -q
        previous=$directory/$step/f.####.exr
    done
    mv "$directory/$step" "$directory/last"
    exit 0
fi

source "$here/../common.sh"
bench_require_packages python3-numpy python3-openimageio time
modestack=${1:?usage: run.sh MODESTACK [WORK]}
work=${2:-/tmp/modestack-layers}
cycles=${CYCLES_DIR:-$here/../../../shared/cycles}
runs=${RUNS:-2}
synthetic=${SYNTHETIC:-1280x720}
mkdir -p "$work"
tsv=$work/times.tsv
: >"$tsv"
all_layers=("${layers[@]}")

# use_layers_of INPUT: `layers` (and LAYERS, for --chained) become those of LAYERS the shot has.
use_layers_of()
{
    local present
    present=$("$modestack" info "$1" | awk 'NR > 1 { print $1 }')
    layers=()
    for layer in "${all_layers[@]}"; do
        grep -Eq "(^|\.)$layer\$" <<<"$present" && layers+=("$layer")
    done
    export LAYERS="${layers[*]}"
    layer_options=()
    for layer in "${layers[@]}"; do layer_options+=(--layer "$layer"); done
}

# time_shot NAME INPUT: the three ways, RUNS times each.
time_shot()
{
    local name=$1 input=$2 run
    for run in $(seq 1 "$runs"); do
        bench_time "$tsv" "$name chained" "$run" "$here/run.sh" --chained "$modestack" "$input" "$work/$name/chained"
        rm -rf "$work/$name/together"
        bench_time "$tsv" "$name together" "$run" "$modestack" denoise "$input" "${layer_options[@]}" \
            -o "$work/$name/together/f.####.exr" --json "$work/$name/together.json" -q
        rm -rf "$work/$name/joint"
        bench_time "$tsv" "$name joint" "$run" "$modestack" denoise "$input" "${layer_options[@]}" --joint \
            -o "$work/$name/joint/f.####.exr" --json "$work/$name/joint.json" -q
    done
    # The one run must give the chained runs' pixels and sigma, layer by layer.
    /usr/bin/python3 - "$work/$name/together" "$work/$name/chained/last" "${layers[@]}" <<'PYTHON'
import glob, os, sys
import OpenImageIO as oiio
together, chained, layers = sys.argv[1], sys.argv[2], sys.argv[3:]
for path in sorted(glob.glob(os.path.join(together, "f.*.exr"))):
    a, b = oiio.ImageBuf(path), oiio.ImageBuf(os.path.join(chained, os.path.basename(path)))
    for layer in layers:
        wanted = [n for n in a.spec().channelnames
                  if n.split(".")[-2:-1] == [layer] or n.split(".")[-3:-1] == [layer, "sigma"]]
        assert len(wanted) == 6, (path, layer, wanted)
        pixels = [oiio.ImageBufAlgo.channels(image, tuple(wanted)).get_pixels(oiio.FLOAT) for image in (a, b)]
        if not (pixels[0] == pixels[1]).all():
            sys.exit(f"bench: {path} {layer}: the one run differs from the chained runs")
PYTHON
    echo "bench: $name: the one run gives the chained runs' bits in every layer of every frame" >&2
}

# relmse SEQ REF LAYER: the shot's relMSE of LAYER.
relmse()
{
    "$modestack" compare "$1" "$2" --layer "$3" --json "$work/c.json" -q >/dev/null || true
    /usr/bin/python3 -c 'import json,sys; print("%.5g" % json.load(open(sys.argv[1]))["shot"]["relative_mse"])' "$work/c.json"
}

summary=$work/summary.md
{
    echo "# Several layers in one run — $(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
    echo
} >"$summary"
for shot in sweep_room spin_room; do
    [ -d "$cycles/$shot/spp4" ] || { echo "bench: $cycles/$shot absent: skipped" >&2; continue; }
    input=$cycles/$shot/spp4/frame.####.exr
    reference=$cycles/$shot/ref/frame.####.exr
    use_layers_of "$input"
    time_shot "$shot" "$input"
    {
        echo "## $shot (Cycles, 48 frames 160x120, 4 spp against 512 spp)"
        echo
        echo "The reference's own relMSE is about the input's × 4/512; relMSE below that floor is not resolved."
        echo
        echo "| layer | noisy | own modes (N) | joint (N) | reference floor |"
        echo "|---|---:|---:|---:|---:|"
        for i in "${!layers[@]}"; do
            layer=${layers[$i]}
            noisy=$(relmse "$input" "$reference" "$layer")
            own=$(relmse "$work/$shot/together/f.####.exr" "$reference" "$layer")
            joint=$(relmse "$work/$shot/joint/f.####.exr" "$reference" "$layer")
            own_n=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["layers"][int(sys.argv[2])]["rank"]["n"])' "$work/$shot/together.json" "$i")
            joint_n=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["rank"]["n"])' "$work/$shot/joint.json")
            floor=$(/usr/bin/python3 -c 'import sys; print("%.2g" % (float(sys.argv[1]) * 4 / 512))' "$noisy")
            echo "| $layer | $noisy | $own ($own_n) | $joint ($joint_n) | $floor |"
        done
        echo
    } >>"$summary"
done

if [ -n "$synthetic" ]; then
    maker=$(dirname "$modestack")/../bench/bench_make_noisy_sequence
    shot=$work/synthetic
    if [ ! -f "$shot/done" ]; then
        mkdir -p "$shot"
        for i in "${!all_layers[@]}"; do
            "$maker" --size "$synthetic" --frames 48 --seed $((i + 1)) -o "$shot/l$i.%04d.exr" >/dev/null
        done
        for frame in $(seq -f %04g 1 48); do
            arguments=()
            for i in "${!all_layers[@]}"; do
                arguments+=("$shot/l$i.$frame.exr" --chnames "${all_layers[$i]}.R,${all_layers[$i]}.G,${all_layers[$i]}.B")
                ((i > 0)) && arguments+=(--chappend)
            done
            oiiotool "${arguments[@]}" --compression zip -o "$shot/in.$frame.exr"
        done
        rm -f "$shot"/l*.exr
        touch "$shot/done"
    fi
    use_layers_of "$shot/in.####.exr"
    time_shot "synthetic_$synthetic" "$shot/in.####.exr"
fi

{
    echo "## Time (min of $runs runs; seconds, MB)"
    echo
    echo "| shot and way | wall | CPU | peak RSS |"
    echo "|---|---:|---:|---:|"
    awk -F'\t' '{ key = $1; cpu = $4 + $5; if (!(key in wall) || $3 < wall[key]) wall[key] = $3;
                  if (!(key in best) || cpu < best[key]) best[key] = cpu; if ($6 > rss[key]) rss[key] = $6;
                  if (!(key in order)) { order[key] = ++n; names[n] = key } }
         END { for (i = 1; i <= n; ++i) { k = names[i]; printf "| %s | %.2f | %.2f | %.0f |\n", k, wall[k], best[k], rss[k] / 1024 } }' "$tsv"
} >>"$summary"
cat "$summary"
