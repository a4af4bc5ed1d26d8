"""The shots of bench/conventions/run.sh: our renderer's frames renamed into each
renderer's naming of the conventions table (share/conventions.json), single-part
and, for the renderers that usually write parts, multi-part.

Only names change: every value is our renderer's (DiffInd is not multiplied by
DiffCol as Arnold's diffuse_indirect would be), so that the denoised pixels can
be compared across the renamings. Run as
    styles.py SOURCE_DIR OUT_DIR STYLE...
to write OUT_DIR/<style>/f.####.exr from SOURCE_DIR/f.####.exr.
"""
import glob
import os
import sys

import OpenImageIO as oiio

# Our layers under each renderer's names: "new" gives new.<component>, "" the
# bare components (a beauty's R, G, B, A), "=name" the one channel `name`.
# Layers not named here (Position, Rendered, ...) are left out.
_ARNOLD = {"Combined": "", "DiffDir": "diffuse_direct", "DiffInd": "diffuse_indirect",
           "DiffCol": "diffuse_albedo", "Emit": "emission", "Normal": "N", "Depth": "=Z",
           "DiffIndVar": "diffuse_indirect_variance"}
_KARMA = {"Combined": "C", "DiffDir": "directdiffuse", "DiffInd": "indirectdiffuse", "DiffCol": "albedo",
          "Emit": "directemission", "Normal": "N", "Depth": "=depth",
          "DiffIndVar": "indirectdiffuse_variance"}
_REDSHIFT = {"Combined": "", "DiffDir": "DiffuseLightingRaw", "DiffInd": "GIRaw", "DiffCol": "DiffuseFilter",
             "Emit": "Emission", "Normal": "N", "Depth": "=Z"}

# name: the renderer the naming is of, the --layer denoised, the renaming, the
# header attributes added (none: detection from the names alone), and for a
# multi-part shot the name of the beauty's part (the other parts are named by
# their layer, their channels bare).
STYLES = {
    "modestack": {"renderer": "modestack", "layer": "DiffInd", "names": None},
    "cycles": {"renderer": "cycles", "layer": "ViewLayer.DiffInd",
               "names": {layer: "ViewLayer." + layer
                         for layer in ("Combined", "DiffDir", "DiffInd", "DiffCol", "Emit", "Normal",
                                       "Depth", "DiffIndVar")}},
    # The same with the header attribute Blender writes into every multilayer EXR.
    "cycles-header": {"renderer": "cycles", "layer": "ViewLayer.DiffInd",
                      "names": {layer: "ViewLayer." + layer
                                for layer in ("Combined", "DiffDir", "DiffInd", "DiffCol", "Emit", "Normal",
                                              "Depth", "DiffIndVar")},
                      "attributes": {"BlenderMultiChannel": "Blender V2.55.1 and newer"}},
    "arnold": {"renderer": "arnold", "layer": "diffuse_indirect", "names": _ARNOLD},
    "arnold-multipart": {"renderer": "arnold", "layer": "diffuse_indirect", "names": _ARNOLD,
                         "beauty_part": "RGBA"},
    "renderman": {"renderer": "renderman", "layer": "indirectDiffuse",
                  "names": {"Combined": "Ci", "DiffDir": "directDiffuse", "DiffInd": "indirectDiffuse",
                            "DiffCol": "albedo", "Emit": "emissive", "Normal": "normal",
                            "Depth": "=zfiltered", "DiffIndVar": "indirectDiffuse_mse"}},
    "karma": {"renderer": "karma", "layer": "indirectdiffuse", "names": _KARMA},
    "karma-multipart": {"renderer": "karma", "layer": "indirectdiffuse", "names": _KARMA, "beauty_part": "C"},
    "vray": {"renderer": "vray", "layer": "VRayRawGlobalIllumination",
             "names": {"Combined": "", "DiffDir": "VRayRawLighting", "DiffInd": "VRayRawGlobalIllumination",
                       "DiffCol": "VRayDiffuseFilter", "Emit": "VRaySelfIllumination",
                       "Normal": "VRayNormals", "Depth": "=VRayZDepth"}},
    "redshift": {"renderer": "redshift", "layer": "GIRaw", "names": _REDSHIFT},
    "redshift-multipart": {"renderer": "redshift", "layer": "GIRaw", "names": _REDSHIFT,
                           "beauty_part": "Beauty"},
}
# Our guide and variance layers, by kind: what each renaming should be found under.
SOURCE_LAYERS = {"albedo": "DiffCol", "normal": "Normal", "depth": "Depth", "variance": "DiffIndVar"}


def renamed(style, kind):
    """The name the guide or variance `kind` has in `style`'s files ('' when left out)."""
    names = STYLES[style]["names"]
    source = SOURCE_LAYERS[kind]
    if names is None:
        return source
    name = names.get(source)
    if name is None:
        return ""
    if name.startswith("="):
        return name[1:]
    return name


def _channels(spec):
    return list(spec.channelnames)


def _write(path, parts, attributes):
    """parts: [(part name or None, [(channel, TypeDesc, pixel column)])], one part = single-part."""
    specs = []
    for part_name, columns in parts:
        height, width = columns[0][2].shape
        spec = oiio.ImageSpec(width, height, len(columns), "half")
        spec.channelnames = tuple(name for name, _, _ in columns)
        spec.channelformats = tuple(fmt for _, fmt, _ in columns)
        spec.alpha_channel = -1
        spec.attribute("compression", "zip")
        for key, value in attributes.items():
            spec.attribute(key, value)
        if part_name is not None:
            spec.attribute("oiio:subimagename", part_name)
        specs.append(spec)
    output = oiio.ImageOutput.create(path)
    if output is None or not output.open(path, specs):
        sys.exit(f"styles.py: cannot write {path}: {oiio.geterror()}")
    import numpy
    for index, (spec, (_, columns)) in enumerate(zip(specs, parts)):
        if index > 0 and not output.open(path, spec, "AppendSubimage"):
            sys.exit(f"styles.py: cannot append a part to {path}: {output.geterror()}")
        pixels = numpy.stack([column for _, _, column in columns], axis=-1).astype(numpy.float32)
        if not output.write_image(pixels):
            sys.exit(f"styles.py: cannot write {path}: {output.geterror()}")
    output.close()


def restyle_frame(source, target, style):
    definition = STYLES[style]
    image = oiio.ImageInput.open(source)
    if image is None:
        sys.exit(f"styles.py: cannot read {source}: {oiio.geterror()}")
    spec = image.spec()
    pixels = image.read_image(0, 0, 0, spec.nchannels, "float")
    image.close()
    # Grouped by target layer, in the source's channel order: (target layer, component, type, column).
    groups = {}
    for index, channel in enumerate(_channels(spec)):
        layer, _, component = channel.rpartition(".")
        new = definition["names"].get(layer)
        if new is None:
            continue
        if new.startswith("="):
            key, channel_name = new[1:], new[1:]
        else:
            key, channel_name = new, (f"{new}.{component}" if new else component)
        groups.setdefault(key, []).append((channel_name, component, spec.channelformat(index), pixels[:, :, index]))
    attributes = definition.get("attributes", {})
    if "beauty_part" not in definition:
        columns = [(name, fmt, column) for group in groups.values() for name, _, fmt, column in group]
        _write(target, [(None, columns)], attributes)
        return
    # A part per layer, its channels bare: a one-channel layer ("=Z") keeps its channel name.
    parts = []
    for key, group in groups.items():
        part_name = key if key else definition["beauty_part"]
        single = len(group) == 1 and group[0][0] == key
        parts.append((part_name, [(name if single else component, fmt, column)
                                  for name, component, fmt, column in group]))
    _write(target, parts, attributes)


def main():
    source_dir, out_dir, styles = sys.argv[1], sys.argv[2], sys.argv[3:]
    frames = sorted(glob.glob(os.path.join(source_dir, "f.[0-9][0-9][0-9][0-9].exr")))
    if not frames:
        sys.exit(f"styles.py: no frames f.####.exr in {source_dir}")
    for style in styles:
        if STYLES[style]["names"] is None:
            continue  # our own frames, as rendered
        os.makedirs(os.path.join(out_dir, style), exist_ok=True)
        for frame in frames:
            restyle_frame(frame, os.path.join(out_dir, style, os.path.basename(frame)), style)


if __name__ == "__main__":
    main()
