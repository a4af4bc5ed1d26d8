#!/usr/bin/env bash
# Renders a Cycles shot with Blender (Debian 12 package): SHOT=orbit_cross_room
# (the default) or SHOT=pan_room (a camera pan over glossy and metal surfaces;
# noisy, ref_a and ref_b only). 48 frames at 128x96, noisy (4 spp, seed 1) and two references with other seeds
# (512 spp, seeds 7 and 8) so that scoring can count the reference's own noise,
# and `without`: frames 20-29 at 512 spp (seed 9) without the crossing sphere, to
# find the pixels of the sphere and its shadow (bench/cycles/per_frame.py), and
# `noisy_fixed`: the noisy pass with Cycles' default fixed seed (the same random
# numbers in every frame: noise that repeats, docs/design.md).
#
#   bench/cycles/render.sh OUTDIR
# Writes OUTDIR/{noisy,ref_a,ref_b,without,noisy_fixed}/frame.####.exr, a timing.json in each, and
# OUTDIR/render.log (one line per variant: wall and CPU seconds, load average).
# Environment: SHOT (orbit_cross_room), FRAMES (1-48), RES (128x96), REF_SPP (512). A variant that holds
# a "done" file is kept. ~22 min wall on the 2-core machine of 2026-12-05 (shared
# with another job; ~5.5 s per 512-spp frame unloaded).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: render.sh OUTDIR}
frames=${FRAMES:-1-48}
res=${RES:-128x96}
ref_spp=${REF_SPP:-512}
shot=${SHOT:-orbit_cross_room}
[ -f "$here/$shot.py" ] || { echo "render.sh: no shot $shot ($here/$shot.py)" >&2; exit 1; }

if ! command -v blender > /dev/null; then
    [ -r /etc/debian_version ] || { echo "render.sh: blender missing and this is not Debian" >&2; exit 1; }
    apt-get install -y blender
fi
mkdir -p "$out"
log=$out/render.log
echo "# $(date -u +%FT%TZ) $shot, $(blender --version | head -1), $(nproc) cores, frames $frames, $res" >> "$log"

# variant NAME SPP SEED FRAMES [OPTIONS]
variant()
{
    local name=$1 spp=$2 seed=$3 range=$4 directory=$out/$1
    shift 4
    [ -f "$directory/done" ] && { echo "$name: kept" >> "$log"; return; }
    rm -rf "$directory"
    local load_before
    load_before=$(cut -d' ' -f1-3 /proc/loadavg)
    local start=$SECONDS
    /usr/bin/time -f '%e %U %S' -o "$out/$name.time" \
        nice blender -b -t 2 -P "$here/$shot.py" -- --spp "$spp" --seed "$seed" \
        --frames "$range" --res "$res" --out "$directory" "$@" > "$out/$name.blender.log" 2>&1
    read -r wall user sys < "$out/$name.time"
    echo "$name: ${spp} spp seed $seed frames $range $*, wall ${wall} s, cpu $(echo "$user + $sys" | bc) s," \
        "load before $load_before, after $(cut -d' ' -f1-3 /proc/loadavg)" >> "$log"
    touch "$directory/done"
}

variant noisy 4 1 "$frames"
variant ref_a "$ref_spp" 7 "$frames"
variant ref_b "$ref_spp" 8 "$frames"
if [ "$shot" = orbit_cross_room ]; then
    variant without "$ref_spp" 9 20-29 --without-crosser
    variant noisy_fixed 4 1 "$frames" --fixed-seed
fi
cat "$log"
