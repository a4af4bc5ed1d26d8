#!/usr/bin/env bash
# Object-space benchmark (issue 10): moving cameras against a high-spp reference.
# Not a test: it never fails on quality.
#
# For the built-in `flythrough` shot (48 frames) and the committed glTF room
# (testdata/gltf/room.gltf, 24 frames, moving camera and object) at SIZE (160x120):
#  1. renders a reference at REF_SPP (1024, seed 7; kept and reused for the same SIZE and REF_SPP) and the input at SPP (4, seed 1)
#     with `render --points` (bake + PointLookup);
#  2. denoises the input's DiffInd three ways: image space as shipped (mode filter),
#     image space with --no-mode-filter (the pure temporal low-rank method the
#     object space replaces), and `denoise --object-space`;
#  3. scores everything with `modestack compare --layer DiffInd` against the
#     reference and writes bench/results/object_space.md: relMSE, PSNR, flicker,
#     equivalent spp c/(e - b) with c = e_noisy / (1/SPP + 1/REF_SPP) and b = c/REF_SPP
#     (docs/design.md, "How quality is measured", with c from the input alone), and
#     bench/results/object_space_<shot>.png (noisy | image space --no-mode-filter |
#     image space | object space | reference of one frame, DiffInd tone-mapped).
# Environment: OBJECT_DIR (work files, default /tmp/modestack-object), BUILD_DIR
# (default $OBJECT_DIR/build; an existing Release build skips building), SIZE, SPP,
# REF_SPP, POINT_COUNT (default: width x height), SHOW_FRAME (default 12, within both shots).
# Takes ~20 min on 2 idle cores, nearly all of it the two references.
# Needs /usr/bin/python3 with python3-numpy and python3-openimageio.
set -euo pipefail
cd "$(dirname "$0")/../.."
repository=$PWD
work=${OBJECT_DIR:-/tmp/modestack-object}
build_dir=${BUILD_DIR:-$work/build}
size=${SIZE:-160x120}
spp=${SPP:-4}
ref_spp=${REF_SPP:-1024}
show_frame=${SHOW_FRAME:-12}
mkdir -p "$work" "$repository/bench/results"
source bench/common.sh
bench_require_packages python3-numpy python3-openimageio
if [[ ! -x $build_dir/app/modestack ]]; then
    cmake -S "$repository" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$build_dir" --target modestack
fi
modestack=$build_dir/app/modestack
points_option=()
[[ -n ${POINT_COUNT:-} ]] && points_option=(--point-count "$POINT_COUNT")

seconds_of() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['$2'])" "$1"; }

for shot in flythrough gltf_room; do
    scene=$shot
    [[ $shot == gltf_room ]] && scene=$repository/testdata/gltf/room.gltf
    dir=$work/$shot
    mkdir -p "$dir"
    if [[ $(cat "$dir/ref.key" 2>/dev/null) != "$size $ref_spp" ]]; then
        rm -rf "$dir/ref"
        "$modestack" render --scene "$scene" --size "$size" --spp "$ref_spp" --seed 7 -q \
            -o "$dir/ref/r.####.exr" --json "$dir/ref.json"
        echo "$size $ref_spp" > "$dir/ref.key"
    fi
    rm -rf "$dir/noisy" "$dir/points" "$dir/image" "$dir/image_temporal" "$dir/object"
    start=$(date +%s.%N)
    "$modestack" render --scene "$scene" --size "$size" --spp "$spp" --seed 1 -q "${points_option[@]}" \
        --points "$dir/points/p.####.exr" -o "$dir/noisy/n.####.exr" --json "$dir/noisy.json"
    "$modestack" denoise "$dir/noisy/n.####.exr" --layer DiffInd -q -o "$dir/image/d.####.exr" \
        --json "$dir/image.json"
    "$modestack" denoise "$dir/noisy/n.####.exr" --layer DiffInd --no-mode-filter -q \
        -o "$dir/image_temporal/d.####.exr" --json "$dir/image_temporal.json"
    "$modestack" denoise "$dir/noisy/n.####.exr" --layer DiffInd --object-space "$dir/points/p.####.exr" -q \
        -o "$dir/object/d.####.exr" --json "$dir/object.json"
    for result in noisy/n image/d image_temporal/d object/d; do
        "$modestack" compare "$dir/$result.####.exr" "$dir/ref/r.####.exr" --layer DiffInd -q \
            --json "$dir/${result%%/*}.cmp.json" >/dev/null || true  # exits 2 on FAILURE: we want the figures
    done
done

/usr/bin/python3 - "$work" "$repository/bench/results" "$spp" "$ref_spp" "$show_frame" <<'PY'
import json, os, sys, datetime, platform
import numpy, OpenImageIO as oiio
work, results, spp, ref_spp, show = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
load = lambda path: json.load(open(path))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
lines = [f"# Object-space denoising (issue 10)", "",
         f"bench/object_space/run.sh, {datetime.date.today()}, {os.cpu_count()} cores ({cpu}). "
         f"Input {spp} spp, reference {ref_spp} spp (seed 7), DiffInd against the reference "
         "(`modestack compare`). Equivalent spp = c/(e - b), c = e_noisy/(1/spp + 1/ref_spp), "
         "b = c/ref_spp; (≥ c/e) is the lower bound if the reference were exact. Seconds: the render "
         "(noisy: camera and bake) or the denoise alone; speed-up: rendering the equivalent spp "
         "(time per spp from the reference render) against our render + denoise (image space: the camera "
         "frames only, object space: with the bake).", ""]
names = {"noisy": f"noisy {spp} spp", "image": "image space (mode filter)",
         "image_temporal": "image space, --no-mode-filter", "object": "object space"}
for shot in ("flythrough", "gltf_room"):
    d = os.path.join(work, shot)
    shot_json = lambda name: load(os.path.join(d, f"{name}.cmp.json"))["shot"]
    e_noisy = shot_json("noisy")["relative_mse"]
    c = e_noisy / (1 / spp + 1 / ref_spp)
    b = c / ref_spp
    render = load(os.path.join(d, "noisy.json"))
    reference = load(os.path.join(d, "ref.json"))
    frames = len(render["per_frame"])
    # Render time per frame and spp, from the reference (its fixed cost is negligible at ref_spp).
    seconds_per_spp = reference["render_seconds"] / frames / ref_spp
    points = render.get("points", {})
    lines += [f"## {shot}: {len(render['per_frame'])} frames {render['width']}x{render['height']}, "
              f"{points.get('count', '?')} surface points (spacing {points.get('spacing', 0):.3g} m)", "",
              "| result | relMSE | PSNR dB | flicker | N | equiv. spp (≥ c/e) | seconds | speed-up (≥) |",
              "|---|---:|---:|---:|---:|---|---:|---|"]
    for name in ("noisy", "image", "image_temporal", "object"):
        figures = shot_json(name)
        e = figures["relative_mse"]
        equivalent = c / (e - b) if e > b else float("inf")
        if name == "noisy":
            n, seconds, cost = "", render["render_seconds"], render["render_seconds"]
        else:
            summary = load(os.path.join(d, f"{name}.json"))
            n, seconds = summary["rank"]["n"], summary["seconds"]["total"]
            # Our render + the denoise; image space needs no bake: its camera frames alone.
            camera_seconds = sum(frame["seconds"] for frame in render["per_frame"])
            cost = (render["render_seconds"] if name == "object" else camera_seconds) + seconds
        # Equal-quality speed-up: rendering the equivalent spp against our render + denoise.
        speed_up = frames * seconds_per_spp * equivalent / cost
        lower = frames * seconds_per_spp * (c / e) / cost
        lines.append(f"| {names[name]} | {e:.4g} | {figures['psnr_db']:.2f} | {figures['flicker']:.4g} | {n} | "
                     f"{equivalent:.0f} (≥ {c / e:.0f}) | {seconds:.1f} | {speed_up:.1f}× (≥ {lower:.1f}×) |")
    lines.append("")
    if True:
        def diffind(path):
            image = oiio.ImageBuf(path)
            spec = image.spec()
            channels = [spec.channelindex(f"DiffInd.{c}") for c in "RGB"]
            pixels = image.get_pixels(oiio.FLOAT)
            return pixels[:, :, channels]
        panels = [diffind(os.path.join(d, f"{folder}.{show:04d}.exr"))
                  for folder in ("noisy/n", "image_temporal/d", "image/d", "object/d", "ref/r")]
        strip = numpy.concatenate(panels, axis=1)
        strip = numpy.maximum(numpy.nan_to_num(strip), 0)  # a rebuild may dip below 0
        strip = numpy.ascontiguousarray(numpy.clip((strip / (1 + strip)) ** (1 / 2.2) * 255, 0, 255).astype(numpy.uint8))
        png = os.path.join(results, f"object_space_{shot}.png")
        out = oiio.ImageOutput.create(png)
        out.open(png, oiio.ImageSpec(strip.shape[1], strip.shape[0], 3, oiio.UINT8))
        out.write_image(strip)
        out.close()
        lines += [f"![{shot} frame {show}](object_space_{shot}.png)", "",
                  f"{shot} frame {show}, DiffInd tone-mapped, left to right: noisy, image space --no-mode-filter, "
                  "image space, object space, reference.", ""]
open(os.path.join(results, "object_space.md"), "w").write("\n".join(lines))
print("\n".join(lines))
PY
