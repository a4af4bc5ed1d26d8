#!/usr/bin/python3
"""Where a denoised shot is worse than its noisy input: per-frame relMSE and
relMSE over chosen regions, with the reference's own noise counted as in
bench/estimators/scenes.py (reference = mean of two seeds A and B, its noise
n = box3((A - B)^2 / 4) is taken off every squared error).

  per_frame.py NOISY REF_A REF_B LAYER DENOISED... [--changed FIRST-LAST]...
               [--without REF_WITHOUT FIRST-LAST [--region-layer L]]

--changed F-L   region: pixels of frames F..L whose reference differs from its
                temporal median (scenes.py's --transient), may be repeated
--without P F-L region: pixels of frames F..L where the reference differs from
                P, a reference of those frames rendered without the transient
                object (orbit_cross_room.py --without-crosser): the object and
                its shadow only; --region-layer L compares layer L instead of
                LAYER (DiffInd's reference noise alone crosses the threshold)
Prints one row per frame (noisy relMSE, each denoised shot as a multiple of it,
'!' where above 1) and one row per region (its share of the pixels of the frames
it touches, the relMSE of each shot over it).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'estimators'))
from prototype import box, read_shot, transient_mask  # noqa: E402


def relative(squared, ref):
    return squared / (ref ** 2 + 0.01)


def frames_mask(shape, first, last, pixels):
    frames = np.zeros((shape[0], 1, 1, 1), dtype=bool)
    frames[first - 1:last] = True
    return np.broadcast_to(pixels & frames, shape)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('noisy'), parser.add_argument('ref_a'), parser.add_argument('ref_b')
    parser.add_argument('layer'), parser.add_argument('denoised', nargs='+')
    parser.add_argument('--changed', action='append', default=[])
    parser.add_argument('--without', nargs=2, metavar=('PATTERN', 'FIRST-LAST'))
    parser.add_argument('--region-layer', help='the layer --without compares (default LAYER); a '
                        'low-noise one, since a single reference\'s noise also crosses the threshold')
    args = parser.parse_args()
    a, b = read_shot(args.ref_a, args.layer), read_shot(args.ref_b, args.layer)
    ref, noise = (a + b) / 2, box((a - b) ** 2 / 4, 1)
    names = ['noisy'] + [p.split('/')[-2] for p in args.denoised]
    rels = [relative((read_shot(p, args.layer) - ref) ** 2 - noise, ref)
            for p in [args.noisy] + args.denoised]

    regions = []
    for span in args.changed:
        first, last = (int(v) for v in span.split('-'))
        regions.append((f'changed {span}', transient_mask(ref, first, last)))
    if args.without:
        first, last = (int(v) for v in args.without[1].split('-'))
        region_layer = args.region_layer or args.layer
        other = read_shot(args.without[0], region_layer)
        if len(other) != last - first + 1:
            raise SystemExit(f"{args.without[0]}: {len(other)} frames, expected {last - first + 1}")
        differs = np.zeros(ref.shape[:3] + (1,), dtype=bool)
        window = ref[first - 1:last] if region_layer == args.layer else \
            (read_shot(args.ref_a, region_layer)[first - 1:last] + read_shot(args.ref_b, region_layer)[first - 1:last]) / 2
        differs[first - 1:last] = (np.abs(window - other) > 0.1 * np.abs(window) + 0.01).any(axis=3, keepdims=True)
        regions.append((f'object+shadow {args.without[1]}', frames_mask(ref.shape, first, last, differs)))

    print(f"{args.layer}: frame, noisy relMSE, " + ', '.join(f'{n}/noisy' for n in names[1:]))
    per_frame = [r.mean((1, 2, 3)) for r in rels]
    for f in range(ref.shape[0]):
        ratios = [p[f] / per_frame[0][f] for p in per_frame[1:]]
        print(f"  {f + 1:3d} {per_frame[0][f]:.5f} " +
              ' '.join(f"{x:6.3f}{'!' if x > 1 else ' '}" for x in ratios))
    for label, mask in [('shot', np.ones(ref.shape, dtype=bool))] + regions:
        frames = mask[..., 0].any(axis=(1, 2))
        share = mask[frames][..., 0].mean() * 100  # of the pixels of the frames it touches
        values = [r[mask].mean() for r in rels]
        print(f"  {label:24s} ({share:5.1f} % of its frames' pixels) noisy {values[0]:.5f}; " +
              ', '.join(f"{n} {v:.5f} = {v / values[0]:.3f}x" for n, v in zip(names[1:], values[1:])))


if __name__ == '__main__':
    main()
