#!/usr/bin/python3
"""The fast-light part of bench/quality/run.sh's report (issue 29, "never worse than the input"):
sweep (hard shadows that move every frame) and cross (a small box and its shadow in frames 20-27
only), scored on DiffDir and DiffInd, per frame, so that the worst frame shows. Also the box
region rule the switch table uses: relMSE over the pixels a transient object changes.

Reads the JSON files run.sh leaves in QUALITY_DIR: SCENE/s<M>/{noisy,gaussian,auto}.cmp.json
(DiffInd) and SCENE/direct/s<M>/... (DiffDir), SCENE/direct/fit_s<M>.cmp.json for DiffDir's own
c/s fit (so its reference error b is counted as it is for DiffInd).
"""
import os

import numpy

from quality import GAUSSIAN_SIGMA, fit_c, load, read_layer, sequence_frames

FAST_SCENES = ("sweep", "cross")
CROSS_FRAMES = range(20, 28)  # kCrossFirstFrame..kCrossLastFrame of core/scene/builtin_scenes.h
METHODS = (("noisy", "noisy"), ("gaussian", f"Gaussian {GAUSSIAN_SIGMA} px"), ("auto", "denoise (defaults)"))


def changed_region_relmse(reference_pattern, sequences, frames, background_frames, layer):
    """relMSE of each sequence over the pixels a transient object changes: where the reference of
    a frame in FRAMES differs from the per-pixel median of the reference's BACKGROUND_FRAMES (the
    same lighting, no object) by more than 25 % (any channel). Frame totals dilute such an object,
    which covers a few % of the image. Returns ({name: relMSE}, pixels in the region, pixels)."""
    references = dict(sequence_frames(reference_pattern))
    quiet = [read_layer(references[f], layer) for f in background_frames if f not in frames and f in references]
    background = numpy.median(numpy.stack(quiet), axis=0)
    totals = {name: 0.0 for name in sequences}
    count = pixels = 0
    for frame in frames:
        reference = read_layer(references[frame], layer)
        change = (numpy.abs(reference - background) / (numpy.abs(background) + 0.05)).max(axis=2)
        mask = change > 0.25
        count += int(mask.sum())
        pixels += mask.size
        for name, pattern in sequences.items():
            image = read_layer(dict(sequence_frames(pattern))[frame], layer)
            totals[name] += float(((image - reference) ** 2 / (reference ** 2 + 0.01))[mask].sum())
    return {name: total / (3 * max(count, 1)) for name, total in totals.items()}, count, pixels


def layer_directory(quality_dir, scene, layer, spp):
    base = os.path.join(quality_dir, scene)
    return os.path.join(base, f"s{spp}") if layer == "DiffInd" else os.path.join(base, "direct", f"s{spp}")


def per_frame(path):
    """{frame: relMSE} of a compare JSON."""
    return {entry["frame"]: entry["relative_mse"] for entry in load(path)["per_frame"]}


def direct_b(quality_dir, scene, fit_spp, ref_spp):
    """b = c / ref_spp of DiffDir, c fitted on the noisy renders like DiffInd's (quality.fit_c)."""
    errors = {spp: load(os.path.join(quality_dir, scene, "direct", f"fit_s{spp}.cmp.json"))["shot"]["relative_mse"]
              for spp in fit_spp}
    c, _ = fit_c(errors, ref_spp)
    return c / ref_spp


def collect(quality_dir, models, fit_spp, input_spp, ref_spp):
    """Per scene, layer and input spp: b and the per-frame relMSE of every method."""
    results = []
    for scene in FAST_SCENES:
        if scene not in models or not os.path.isdir(os.path.join(quality_dir, scene, "direct")):
            continue
        for layer in ("DiffDir", "DiffInd"):
            b = direct_b(quality_dir, scene, fit_spp, ref_spp) if layer == "DiffDir" else models[scene].b
            for spp in input_spp:
                directory = layer_directory(quality_dir, scene, layer, spp)
                frames = {key: per_frame(os.path.join(directory, f"{key}.cmp.json")) for key, _ in METHODS}
                results.append({"scene": scene, "layer": layer, "spp": spp, "b": b, "per_frame": frames})
    return results


def mean_over(values, frames):
    chosen = [values[f] for f in frames if f in values]
    return sum(chosen) / len(chosen)


def worst(values):
    frame = max(values, key=values.get)
    return values[frame], frame


def section(quality_dir, models, fit_spp, input_spp, ref_spp):
    """The lines of quality.md's fast-light section and the data of its per-frame plot."""
    results = collect(quality_dir, models, fit_spp, input_spp, ref_spp)
    if not results:
        return [], results
    lines = ["### Fast light: sweep and cross, DiffDir and DiffInd (issue 29)", "",
             "sweep: a small key light 30 cm above the floor circles the room once, so the boxes' hard shadows "
             "move every frame; cross: fixed lighting, a small box and its hard shadow exist in frames "
             f"{CROSS_FRAMES[0]}–{CROSS_FRAMES[-1]} only. relMSE of the whole shot; worst frame = the frame with "
             "the highest relMSE; worst ratio = the highest per-frame denoise / noisy. b = the reference's own "
             "expected relMSE (c / ref spp, c fitted per layer on the noisy renders): a ratio (e − b)/(e_noisy − b) "
             "counts only the error beyond the reference's.", "",
             "| shot | layer | M spp | b | relMSE noisy | Gaussian | denoise | denoise / noisy | (e − b) / (noisy − b) | "
             "worst frame noisy | worst frame denoise | worst ratio denoise / noisy |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for result in results:
        frames = result["per_frame"]
        mean = {key: sum(values.values()) / len(values) for key, values in frames.items()}
        ratios = {f: frames["auto"][f] / frames["noisy"][f] for f in frames["noisy"]}
        b = result["b"]
        excess = "e ≤ b" if mean["auto"] <= b else f'{(mean["auto"] - b) / (mean["noisy"] - b):.3f}'
        worst_noisy, worst_auto, worst_ratio = worst(frames["noisy"]), worst(frames["auto"]), worst(ratios)
        lines.append(f'| {result["scene"]} | {result["layer"]} | {result["spp"]} | {b:.3g} | {mean["noisy"]:.4g} | '
                     f'{mean["gaussian"]:.4g} | {mean["auto"]:.4g} | {mean["auto"] / mean["noisy"]:.3f} | {excess} | '
                     f'{worst_noisy[0]:.4g} (f{worst_noisy[1]}) | {worst_auto[0]:.4g} (f{worst_auto[1]}) | '
                     f'{worst_ratio[0]:.3f} (f{worst_ratio[1]}) |')
    worse = [f'{r["scene"]} {r["layer"]} at {r["spp"]} spp' for r in results
             if sum(r["per_frame"]["auto"].values()) > sum(r["per_frame"]["noisy"].values())]
    if worse:
        lines += ["", "Worse than the input over the whole shot (denoise / noisy > 1): " + ", ".join(worse) + "."]
    lines += cross_lines(quality_dir, results)
    return lines, results


def cross_lines(quality_dir, results):
    """cross: the crossing frames on their own, the box region and the per-frame figures at 4 spp."""
    crossing = [r for r in results if r["scene"] == "cross"]
    if not crossing:
        return []
    lines = ["", f"cross, frames {CROSS_FRAMES[0]}–{CROSS_FRAMES[-1]} (the box crossing) on their own: mean "
             "per-frame relMSE; box region = the pixels of those frames where the reference differs by more "
             "than 25 % from the per-pixel median of the reference's other frames (the box, its shadow, its "
             "colour bleeding), 4-spp input only.", "",
             "| layer | M spp | noisy | Gaussian | denoise | denoise / noisy | box region: noisy | Gaussian | denoise | "
             "denoise / noisy | region pixels |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    reference = os.path.join(quality_dir, "cross", "ref", "f.####.exr")
    for result in crossing:
        frames = result["per_frame"]
        mean = {key: mean_over(values, CROSS_FRAMES) for key, values in frames.items()}
        region_cells = "– | – | – | – | –"
        if result["spp"] == 4:
            directory = layer_directory(quality_dir, "cross", result["layer"], 4)
            sequences = {"noisy": os.path.join(quality_dir, "cross", "noisy_s4", "f.####.exr"),
                         "gaussian": os.path.join(directory, "gaussian", "f.####.exr"),
                         "auto": os.path.join(directory, "auto", "f.####.exr")}
            if all(os.path.isdir(os.path.dirname(path)) for path in sequences.values()):
                all_frames = [frame for frame, _ in sequence_frames(reference)]
                region, count, pixels = changed_region_relmse(reference, sequences, CROSS_FRAMES, all_frames,
                                                              result["layer"])
                region_cells = (f'{region["noisy"]:.4g} | {region["gaussian"]:.4g} | {region["auto"]:.4g} | '
                                f'{region["auto"] / region["noisy"]:.3f} | {count} ({100 * count / pixels:.1f} %)')
        lines.append(f'| {result["layer"]} | {result["spp"]} | {mean["noisy"]:.4g} | {mean["gaussian"]:.4g} | '
                     f'{mean["auto"]:.4g} | {mean["auto"] / mean["noisy"]:.3f} | {region_cells} |')
    at_4 = {r["layer"]: r["per_frame"] for r in crossing if r["spp"] == 4}
    if len(at_4) == 2:
        shown = [f for f in range(CROSS_FRAMES[0] - 2, CROSS_FRAMES[-1] + 3) if f in at_4["DiffDir"]["noisy"]]
        lines += ["", "cross at 4 spp, per frame (crossing frames in bold):", "",
                  "| frame | DiffDir noisy | DiffDir denoise | / noisy | DiffInd noisy | DiffInd denoise | / noisy |",
                  "|---:|---:|---:|---:|---:|---:|---:|"]
        for frame in shown:
            label = f"**{frame}**" if frame in CROSS_FRAMES else str(frame)
            cells = []
            for layer in ("DiffDir", "DiffInd"):
                noisy, auto = at_4[layer]["noisy"][frame], at_4[layer]["auto"][frame]
                cells.append(f"{noisy:.4g} | {auto:.4g} | {auto / noisy:.3f}")
            lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def plot_per_frame(results, path):
    """relMSE per frame at 4 spp: one panel per scene and layer, noisy / Gaussian / denoise."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    shown = [r for r in results if r["spp"] == 4]
    if not shown:
        return False
    figure, axes = plt.subplots(1, len(shown), figsize=(4.6 * len(shown), 3.6), squeeze=False)
    colours = {"noisy": "black", "gaussian": "tab:orange", "auto": "tab:red"}
    for axis, result in zip(axes[0], shown):
        for key, label in METHODS:
            values = result["per_frame"][key]
            frames = sorted(values)
            axis.semilogy(frames, [values[f] for f in frames], ".-", color=colours[key], linewidth=0.8, label=label)
        axis.axhline(result["b"], color="gray", linestyle="--", linewidth=0.8, label="b (reference)")
        if result["scene"] == "cross":
            axis.axvspan(CROSS_FRAMES[0] - 0.5, CROSS_FRAMES[-1] + 0.5, color="tab:blue", alpha=0.1,
                         label="box crossing")
        axis.set_title(f'{result["scene"]} {result["layer"]}, 4 spp')
        axis.set_xlabel("frame")
        axis.set_ylabel("relMSE")
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=6)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return True
