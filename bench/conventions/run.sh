#!/usr/bin/env bash
# The renderer conventions table measured (issue 30's closing note): what
# `modestack denoise` detects, finds and writes for a shot in each renderer's
# naming. Not a test: it reports, it does not judge (a naming that is not
# detected or a guide that is missed is written into the table as a finding).
#
#   bench/conventions/run.sh MODESTACK [WORK]
#
# 1. Renders a small shot with our renderer (MODESTACK render --scene switch,
#    64x48, frames 1-8, 2 spp) into WORK/ours.
# 2. Renames its layers into each renderer's names of share/conventions.json
#    (bench/conventions/styles.py: light layer, albedo/normal/depth guides,
#    variance where the convention has one, beauty), single-part, and for
#    Arnold, Karma and Redshift also multi-part (a part per AOV, bare channels);
#    the Cycles-style shot once more with the header attribute Blender writes.
# 3. Runs `denoise --layer <the renderer's indirect diffuse> --json` on each,
#    without --renderer.
# 4. Writes the table (bench/conventions/report.py) to
#    bench/results/conventions.md: the renderer detected and from what, the
#    guides and variance found under which names, the beauty update, the output
#    channels, and whether the denoised pixels equal the Cycles-style shot's.
#
# WORK defaults to /tmp/modestack-conventions; it is emptied first.
set -euo pipefail
if (($# < 1 || $# > 2)); then
    echo "usage: $0 MODESTACK [WORK]" >&2
    exit 2
fi
modestack=$(realpath "$1")
work=${2:-/tmp/modestack-conventions}
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
python=/usr/bin/python3
source "$repo/bench/common.sh"
bench_require_packages python3-numpy python3-openimageio
machine=$(bench_machine)
styles=(modestack cycles cycles-header arnold arnold-multipart renderman karma karma-multipart vray redshift
    redshift-multipart)

rm -rf "$work"
mkdir -p "$work"
echo "conventions: rendering our shot into $work/ours" >&2
"$modestack" render --scene switch --size 64x48 --frames 1-8 --spp 2 -o "$work/ours/f.####.exr" -q
"$python" "$here/styles.py" "$work/ours" "$work" "${styles[@]}"

for style in "${styles[@]}"; do
    input=$work/$style/f.####.exr
    [[ $style == modestack ]] && input=$work/ours/f.####.exr
    layer=$("$python" -c "import sys; sys.path.insert(0, '$here'); import styles; print(styles.STYLES['$style']['layer'])")
    echo "conventions: $style: denoise --layer $layer" >&2
    "$modestack" denoise "$input" --layer "$layer" -q --json "$work/$style.json" \
        -o "$work/$style.denoised/d.####.exr" 2>"$work/$style.stderr" || echo $? >"$work/$style.exit"
done

"$python" "$here/report.py" "$work" "$modestack" "bench/conventions/run.sh $*" "$machine" "${styles[@]}" \
    >"$repo/bench/results/conventions.md"
echo "conventions: wrote $repo/bench/results/conventions.md" >&2
