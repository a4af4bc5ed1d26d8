"""The Markdown table of bench/conventions/run.sh, from each shot's --json
summary and output frames:

    report.py WORK MODESTACK COMMAND MACHINE STYLE...

Per shot: the renderer detected and from what; the guides and variance found
(and a finding where the shot has one under a name the convention lists and it
was not found, or the renderer was not the one whose naming the shot has); the
beauty update; the output's channels (per part); and whether the denoised
layer and its sigma hold the same values as the Cycles-style shot's.
"""
import glob
import json
import os
import sys

import numpy
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import styles  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
REFERENCE = "cycles"


def read_parts(path):
    """[(part name, [channel names])] and {flattened channel name: values}, multi-part files read
    as modestack reads them (io/layers.h, part_channel_names: a part with a bare channel puts
    every channel in the layer its name makes)."""
    image = oiio.ImageInput.open(path)
    if image is None:
        raise RuntimeError(f"cannot read {path}: {oiio.geterror()}")
    parts, values = [], {}
    subimage = 0
    while image.seek_subimage(subimage, 0):
        spec = image.spec()
        name = spec.getattribute("oiio:subimagename") or ""
        channels = list(spec.channelnames)
        pixels = image.read_image(subimage, 0, 0, spec.nchannels, "float")
        named = bool(name) and any("." not in channel for channel in channels)
        for index, channel in enumerate(channels):
            values[f"{name}.{channel}" if named else channel] = pixels[:, :, index]
        parts.append((name, channels))
        subimage += 1
    image.close()
    return parts, values


def denoised_values(output_dir, layer):
    """The denoised layer's R, G, B and sigma of every output frame, in one array (None if absent)."""
    arrays = []
    for frame in sorted(glob.glob(os.path.join(output_dir, "d.*.exr"))):
        _, values = read_parts(frame)
        for name in (layer, layer + ".sigma"):
            for component in "RGB":
                channel = f"{name}.{component}"
                if channel not in values:
                    return None
                arrays.append(values[channel])
    return numpy.stack(arrays) if arrays else None


def compare(values, reference):
    """'yes' when every value is the same, else how many differ and by how much."""
    if values is None or reference is None:
        return "no (layer or sigma missing)"
    if values.shape != reference.shape:
        return "no (different sizes)"
    if numpy.array_equal(values, reference):
        return "yes"
    differ = numpy.count_nonzero(values != reference)
    return f"no: {differ} of {values.size} values differ, max abs diff {numpy.max(numpy.abs(values - reference)):.3g}"


def convention(table, name):
    for row in table["renderers"]:
        if row["name"] == name:
            return row
    return None


def listed_names(row, kind, layer):
    """The names the convention looks for a guide (or the variance of `layer`) under."""
    if row is None:
        return []
    if kind == "variance":
        short = layer.rpartition(".")[2] if layer.startswith("ViewLayer.") else layer
        return [pattern.replace("{layer}", short) for pattern in
                row.get("variance_by_layer", {}).get(short, []) + row.get("variance", [])]
    return row.get("guides", {}).get(kind, [])


def shown(names):
    return ", ".join(names) if names else "—"


def main():
    work, modestack, command, machine = sys.argv[1:5]
    shots = sys.argv[5:]
    with open(os.path.join(REPO, "share", "conventions.json")) as handle:
        table = json.load(handle)
    version = os.popen(f"'{modestack}' --version 2>/dev/null").read().strip()
    commit = os.popen(f"git -C '{REPO}' rev-parse --short HEAD 2>/dev/null").read().strip()
    reference = denoised_values(os.path.join(work, REFERENCE + ".denoised"), styles.STYLES[REFERENCE]["layer"])

    rows, details, findings = [], [], []
    seen = {}  # shot -> (the kinds found, its denoised values)
    with open(os.path.join(work, REFERENCE + ".json")) as handle:
        lookups = json.load(handle)["renderer"]
    reference_kinds = tuple(kind for kind in ("albedo", "normal", "depth", "variance")
                            if (lookups["variance"] if kind == "variance" else lookups["guides"][kind]).get("found"))
    for shot in shots:
        style = styles.STYLES[shot]
        parts = "multi" if "beauty_part" in style else "single"
        summary_path = os.path.join(work, shot + ".json")
        if not os.path.exists(summary_path):
            with open(os.path.join(work, shot + ".stderr")) as handle:
                error = handle.read().strip()
            rows.append(f"| {shot} | {parts} | {style['layer']} | failed: {error} | | | | | | | |")
            findings.append(f"**{shot}**: denoise failed: {error}")
            continue
        with open(summary_path) as handle:
            summary = json.load(handle)
        renderer = summary["renderer"]
        row = convention(table, style["renderer"])
        if renderer["name"] != style["renderer"]:
            findings.append(f"**{shot}**: detected as {renderer['name']} ({renderer['detected_by']}), "
                            f"not {style['renderer']}: by layer names alone it matched as many of "
                            f"{renderer['name']}'s detection layers as of {style['renderer']}'s, and a tie "
                            f"goes to the first in table order.")
        found = {}
        for kind in ("albedo", "normal", "depth", "variance"):
            lookup = renderer["variance"] if kind == "variance" else renderer["guides"].get(kind, {})
            found[kind] = lookup.get("found")
            written = styles.renamed(shot, kind)
            prefix = "ViewLayer." if style["layer"].startswith("ViewLayer.") else ""
            short = written[len(prefix):] if written.startswith(prefix) else written
            if written and short in listed_names(row, kind, style["layer"]) and found[kind] != written:
                findings.append(f"**{shot}**: the {kind} layer {written} is in the shot and in the "
                                f"{style['renderer']} convention's names, but was "
                                f"{'found as ' + str(found[kind]) if found[kind] else 'not found'} "
                                f"(looked for {shown(lookup.get('looked_for', []))}).")

        def cell(kind):
            return f"`{found[kind]}`" if found[kind] else "not found"

        beauty = summary["beauty"]
        if beauty["updated"]:
            beauty_cell = f"yes: `{beauty['formula']}`"
        else:
            beauty_cell = f"no: {beauty['reason']}"
            if style["renderer"] in ("modestack", "cycles", "arnold", "renderman", "karma", "vray", "redshift"):
                note = ""
                if "beauty_part" in style and "has no beauty the unnamed" in beauty["reason"]:
                    note = (f" Every part of a multi-part EXR has a name, so the beauty's bare R, G, B in "
                            f"part `{style['beauty_part']}` read as `{style['beauty_part']}.R`: the "
                            f"convention's unnamed beauty is never found in a multi-part shot.")
                findings.append(f"**{shot}**: the beauty was not updated: {beauty['reason']}.{note}")
        output_dir = os.path.join(work, shot + ".denoised")
        values = denoised_values(output_dir, style["layer"])
        kinds_found = tuple(kind for kind in found if found[kind])
        if shot == REFERENCE:
            same = "(the reference)"
        else:
            same = compare(values, reference)
            if same != "yes":
                missing = [kind for kind in reference_kinds if kind not in kinds_found]
                if missing:
                    same += f" (expected: no {', '.join(missing)} found)"
                    # Against the first shot that found the same, if any.
                    for other, (other_kinds, other_values) in seen.items():
                        if other_kinds == kinds_found:
                            same += f"; same as {other}: {compare(values, other_values)}"
                            break
                else:
                    findings.append(f"**{shot}**: the same guides and variance as the Cycles-style shot were "
                                    f"found, but the denoised values differ ({same}).")
        seen.setdefault(shot, (kinds_found, values))
        guides = ", ".join(summary["mode_filter"].get("feature_guides", [])) or "none"
        whiten = summary.get("method", {}).get("whiten", {})
        rows.append(f"| {shot} | {parts} | `{style['layer']}` | {renderer['name']} | {renderer['detected_by']} | "
                    f"{cell('albedo')} | {cell('normal')} | {cell('depth')} | {cell('variance')} | {guides} | "
                    f"{beauty_cell} | {same} |")

        first = sorted(glob.glob(os.path.join(output_dir, "d.*.exr")))[0]
        out_parts, _ = read_parts(first)
        lines = [f"### {shot}", ""]
        lines.append(f"- command: `modestack denoise {shot}/f.####.exr --layer {style['layer']} --json "
                     f"{shot}.json -o {shot}.denoised/d.####.exr -q`")
        if whiten:
            lines.append(f"- whitening: {whiten.get('reason', json.dumps(whiten))}")
        if beauty["updated"]:
            lines.append(f"- beauty sigma: `{', '.join(beauty['sigma']['channels'])}` = "
                         f"`{beauty['sigma']['formula']}`")
            for product in beauty.get("products", []):
                lines.append(f"- product AOV: `{product['formula']}`")
        if len(out_parts) == 1:
            lines.append(f"- output channels: {', '.join(out_parts[0][1])}")
        else:
            lines.append(f"- output parts ({len(out_parts)}):")
            for name, channels in out_parts:
                lines.append(f"  - `{name}`: {', '.join(channels)}")
        details.append("\n".join(lines))

    print("# Renderer conventions: what `denoise` detects, finds and writes\n")
    print("Made by `bench/conventions/run.sh` (issue 30); do not edit by hand.\n")
    print(f"- command: `{command}`")
    print(f"- modestack: {version}, built from commit {commit}; conventions: share/conventions.json (built-in table)")
    print(f"- machine: {machine}")
    print("- shot: `modestack render --scene switch --size 64x48 --frames 1-8 --spp 2`, renamed into each "
          "renderer's names by bench/conventions/styles.py (names only: the values stay ours, so that "
          "DiffInd, not DiffCol × DiffInd, is under Arnold's `diffuse_indirect`, and the += Δ of Arnold, RenderMan and Karma is their convention's formula, not a composite these values obey); no header attribute "
          "is added (but to cycles-header), so the renderer is detected from the layer names alone; multi-part shots have a "
          "part per AOV with bare channels, the beauty's part named `RGBA` (Arnold), `C` (Karma), "
          "`Beauty` (Redshift); every run `denoise --layer L --json` without `--renderer`.")
    print("- same as Cycles-style: the denoised layer and its sigma, every pixel of every frame, "
          "equal to the Cycles-style shot's (`ViewLayer.DiffInd`).\n")
    print("| shot | parts | --layer | detected | from | albedo | normal | depth | variance | mode-filter "
          "guides | beauty updated | same as Cycles-style |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print("\n## Findings\n")
    print("\n".join(f"- {finding}" for finding in findings) if findings else "None: every naming was "
          "detected, every guide and variance the shot has under a name of its convention was found, "
          "and every beauty was updated.")
    print("\n## Per shot\n")
    print("\n\n".join(details))


if __name__ == "__main__":
    main()
