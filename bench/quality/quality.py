#!/usr/bin/python3
"""Helpers of bench/quality/run.sh (issue 7): the baselines and the measures (fits, equivalent
spp, speed-up); the tables and plots are in quality_report.py.

Subcommands:
  render-key JSON                       "scene size frames spp seed fixed" of a render --json
  baseline temporal|gaussian IN OUT --json FILE
                                        a baseline of IN's DiffInd layer as OUT/f.####.exr
  best-rank DIR                         the fixed rank with the lowest relMSE in DIR/rank_*.cmp.json
  report QUALITY_DIR RESULTS_DIR ...    quality.md, quality_summary.md, quality.json and
                                        quality_*.png in RESULTS_DIR (quality_report.py)

Every figure follows docs/design.md, "How quality is measured": relMSE and flicker come from
`modestack compare --json`; relMSE(s) = c/s is fitted on the noisy renders (least squares on
log c) with the reference's own expected error b = c/ref_spp added to the model, since the
reference is only 16-256 times cleaner than the inputs; the equivalent spp of an error e is
c/(e - b); the equal-quality speed-up is frames * t(equivalent spp) / (our render time + our
filter time), t(s) = t0 + k*s per frame fitted on the render times. c/e, the same figure as if
the reference were exact, is reported too: a lower bound that stays meaningful when e is close to b.
"""
import argparse
import glob
import json
import math
import os
import re
import sys
import time

import numpy
import OpenImageIO as oiio

TEMPORAL_WINDOW = 5
GAUSSIAN_SIGMA = 1.5


# ---------------------------------------------------------------- sequences and baselines

def sequence_frames(pattern):
    """(frame number, path) of every file of a name.####.exr / name.%04d.exr pattern."""
    directory, name = os.path.split(pattern)
    regex = re.escape(name)
    regex = re.sub(r"(\\#)+", r"(\\d+)", regex)
    regex = re.sub(r"%0\d+d", r"(\\d+)", regex)
    matcher = re.compile("^" + regex + "$")
    found = []
    for entry in os.listdir(directory or "."):
        match = matcher.match(entry)
        if match:
            found.append((int(match.group(1)), os.path.join(directory, entry)))
    if not found:
        raise SystemExit(f"quality.py: no frames match {pattern}")
    return sorted(found)


def layer_channels(spec, layer):
    """Indices of LAYER's R, G, B (DiffInd.R or <prefix>.DiffInd.R)."""
    indices = []
    for component in "RGB":
        matches = [i for i, name in enumerate(spec.channelnames)
                   if name.split(".")[-1] == component and len(name.split(".")) >= 2
                   and name.split(".")[-2] == layer]
        if len(matches) != 1:
            raise SystemExit(f"quality.py: no single {layer}.{component} in {spec.channelnames}")
        indices.append(matches[0])
    return indices


def read_layer(path, layer):
    image = oiio.ImageInput.open(path)
    if image is None:
        raise SystemExit(f"quality.py: cannot read {path}: {oiio.geterror()}")
    spec = image.spec()
    pixels = image.read_image(0, 0, 0, spec.nchannels, "float")
    image.close()
    return numpy.asarray(pixels, dtype=numpy.float64)[:, :, layer_channels(spec, layer)]


def write_layer(path, pixels, layer):
    height, width, _ = pixels.shape
    spec = oiio.ImageSpec(width, height, 3, "float")
    spec.channelnames = (f"{layer}.R", f"{layer}.G", f"{layer}.B")
    spec.attribute("compression", "zip")
    output = oiio.ImageOutput.create(path)
    if output is None or not output.open(path, spec) or \
            not output.write_image(numpy.ascontiguousarray(pixels, dtype=numpy.float32)):
        raise SystemExit(f"quality.py: cannot write {path}: {oiio.geterror()}")
    output.close()


def gaussian_blur(image, sigma):
    """Separable Gaussian, renormalized at the borders (no light enters from outside)."""
    radius = int(math.ceil(3 * sigma))
    offsets = numpy.arange(-radius, radius + 1)
    kernel = numpy.exp(-0.5 * (offsets / sigma) ** 2)
    kernel /= kernel.sum()

    def along(array, axis):
        padded = numpy.moveaxis(array, axis, 0)
        result = numpy.zeros_like(padded)
        length = padded.shape[0]
        for offset, weight in zip(offsets, kernel):
            low, high = max(0, -offset), min(length, length - offset)
            result[low:high] += weight * padded[low + offset:high + offset]
        return numpy.moveaxis(result, 0, axis)

    ones = numpy.ones(image.shape[:2] + (1,))
    weight = along(along(ones, 0), 1)
    return along(along(image, 0), 1) / weight


def baseline(kind, input_pattern, output_directory, json_path, layer="DiffInd"):
    start = time.perf_counter()
    frames = sequence_frames(input_pattern)
    images = [read_layer(path, layer) for _, path in frames]
    read_seconds = time.perf_counter() - start
    os.makedirs(output_directory, exist_ok=True)
    filter_seconds = 0.0
    for index, (frame, _) in enumerate(frames):
        filter_start = time.perf_counter()
        if kind == "temporal":
            half = TEMPORAL_WINDOW // 2
            window = images[max(0, index - half):index + half + 1]
            result = sum(window) / len(window)
        elif kind == "gaussian":
            result = gaussian_blur(images[index], GAUSSIAN_SIGMA)
        else:
            raise SystemExit(f"quality.py: unknown baseline {kind}")
        filter_seconds += time.perf_counter() - filter_start
        write_layer(os.path.join(output_directory, f"f.{frame:04d}.exr"), result, layer)
    with open(json_path, "w") as handle:
        json.dump({"kind": kind, "frames": len(frames), "read_seconds": read_seconds,
                   "filter_seconds": filter_seconds,
                   "seconds": time.perf_counter() - start}, handle, indent=1)


# ---------------------------------------------------------------- reading results

def load(path):
    with open(path) as handle:
        return json.load(handle)


def shot(path):
    return load(path)["shot"]


def best_rank(directory):
    scores = {}
    for path in glob.glob(os.path.join(directory, "rank_*.cmp.json")):
        rank = int(re.search(r"rank_(\d+)\.cmp\.json$", path).group(1))
        scores[rank] = shot(path)["relative_mse"]
    if not scores:
        raise SystemExit(f"quality.py: no rank_*.cmp.json in {directory}")
    return min(scores, key=scores.get), scores


def render_key(path):
    data = load(path)
    print(data["scene"], f'{data["width"]}x{data["height"]}', data["frames"], data["spp"],
          data["seed"], "true" if data["fixed_seed"] else "false")


# ------------------------------------------ the measures of docs/design.md, "How quality is measured"

def fit_c(spp_to_error, ref_spp):
    """c of relMSE(s) = c/s + c/ref_spp, least squares on log c."""
    logs = [math.log(error / (1.0 / spp + 1.0 / ref_spp)) for spp, error in spp_to_error.items()]
    log_c = sum(logs) / len(logs)
    residual = max(abs(value - log_c) for value in logs)
    return math.exp(log_c), residual


def fit_time(spp_to_seconds):
    """t0, k of t(s) = t0 + k*s per frame, least squares on the relative error: the points span
    1..256 spp, and a plain fit would let the slowest render alone decide t0 (even below 0)."""
    spp = numpy.array(list(spp_to_seconds.keys()), dtype=float)
    seconds = numpy.array(list(spp_to_seconds.values()), dtype=float)
    design = numpy.stack([numpy.ones_like(spp), spp], axis=1) / seconds[:, None]
    (t0, k), *_ = numpy.linalg.lstsq(design, numpy.ones_like(seconds), rcond=None)
    return float(t0), float(k)


class SceneModel:
    """The fitted noise and time model of one shot."""

    def __init__(self, name, c, b, ref_spp, t0, k, frames, fit_points, fit_residual, time_points):
        self.name, self.c, self.b, self.ref_spp = name, c, b, ref_spp
        self.t0, self.k, self.frames = t0, k, frames
        self.fit_points, self.fit_residual, self.time_points = fit_points, fit_residual, time_points

    def equivalent_spp(self, error):
        return self.c / (error - self.b) if error > self.b else math.inf

    def lower_equivalent_spp(self, error):
        """c/e: the equivalent spp if the reference were exact, a lower bound (b >= 0)."""
        return self.c / error

    def speed_up(self, error, seconds, lower=False):
        spp = self.lower_equivalent_spp(error) if lower else self.equivalent_spp(error)
        if math.isinf(spp):
            return math.inf
        return self.frames * (self.t0 + self.k * spp) / seconds


def builtin_model(quality_dir, scene, fit_spp, ref_spp, frames):
    errors = {spp: shot(os.path.join(quality_dir, scene, f"fit_s{spp}.cmp.json"))["relative_mse"]
              for spp in fit_spp}
    c, residual = fit_c(errors, ref_spp)
    seconds = {}
    for path in glob.glob(os.path.join(quality_dir, scene, "noisy_s*.json")) + \
            [os.path.join(quality_dir, scene, "ref.json")]:
        render = load(path)
        seconds[render["spp"]] = render["render_seconds"] / len(render["per_frame"])
        frames = len(render["per_frame"])
    t0, k = fit_time(seconds)
    return SceneModel(scene, c, c / ref_spp, ref_spp, t0, k, frames, errors, residual, seconds)


def cycles_model(quality_dir, cycles_dir):
    """spin_room: c from its 4-spp input alone, t(s) through its two measured points."""
    ref_spp = 512
    error = shot(os.path.join(quality_dir, "spin_room", "fit_s4.cmp.json"))["relative_mse"]
    c, residual = fit_c({4: error}, ref_spp)
    seconds = {}
    for variant in ("spp4", "ref"):
        timing = load(os.path.join(cycles_dir, variant, "timing.json"))
        per_frame = [entry["render_s"] for entry in timing["per_frame"].values()]
        seconds[timing["spp"]] = sum(per_frame) / len(per_frame)
        frames = len(per_frame)
    k = (seconds[512] - seconds[4]) / (512 - 4)
    t0 = seconds[4] - 4 * k
    return SceneModel("spin_room", c, c / ref_spp, ref_spp, t0, k, frames, {4: error}, residual, seconds)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="subcommand", required=True)
    key = commands.add_parser("render-key")
    key.add_argument("json")
    base = commands.add_parser("baseline")
    base.add_argument("kind", choices=["temporal", "gaussian"])
    base.add_argument("input")
    base.add_argument("output")
    base.add_argument("--json", required=True)
    base.add_argument("--layer", default="DiffInd")
    best = commands.add_parser("best-rank")
    best.add_argument("directory")
    summary = commands.add_parser("report")
    summary.add_argument("quality_dir")
    summary.add_argument("results_dir")
    summary.add_argument("--scenes", required=True)
    summary.add_argument("--fit-spp", required=True)
    summary.add_argument("--input-spp", required=True)
    summary.add_argument("--ref-spp", type=int, required=True)
    summary.add_argument("--ref-seed", type=int, required=True)
    summary.add_argument("--size", required=True)
    summary.add_argument("--frames", type=int, required=True)
    summary.add_argument("--cycles-dir", required=True)
    summary.add_argument("--machine", required=True)
    summary.add_argument("--command", required=True)
    arguments = parser.parse_args(argv[1:])
    if arguments.subcommand == "render-key":
        render_key(arguments.json)
    elif arguments.subcommand == "baseline":
        baseline(arguments.kind, arguments.input, arguments.output, arguments.json, arguments.layer)
    elif arguments.subcommand == "best-rank":
        print(best_rank(arguments.directory)[0])
    else:
        import quality_report  # matplotlib is only needed here
        quality_report.report(arguments)


if __name__ == "__main__":
    main(sys.argv)
