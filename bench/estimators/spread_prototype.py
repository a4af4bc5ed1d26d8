#!/usr/bin/python3
"""A per-pixel test of the rebuild against the input's spread in time: a
prototype on finished runs (bench/results/estimators.md, section 7). Not a
test and not the binary's rule.

Where the default run kept the rebuild at a pixel, the rebuild is replaced by
the input when the input lies far from it compared with v, the input's spread
around that frame: per side (the K frames before, the K frames after), the mean
over the 3x3 pixels and the side's K frame-to-frame differences of the channel
mean of (y[g+1] - y[g])^2 / 2; the side with the smaller mean is taken (so that a
light switched on just after the frame does not hide the frames before it).
With n = 9K terms in a side:
  below: rebuild - input > z * sqrt(v)
  above: input - rebuild > (sqrt(2n) + z) * sqrt(v)
The judged sample is in every difference, so a lone bright sample (a firefly)
raises v with it: its difference d is one term, d^2/2 <= n*v, and the margin z
allows for its neighbour's own noise. Sigma of a replaced pixel: sqrt(v).

  spread_prototype.py NOISY REF_A REF_B|none LAYER DEFAULT_PATTERN REBUILD_PATTERN
                      [--frames K] [--z Z ...] [--transient FIRST-LAST]

DEFAULT_PATTERN: `denoise` with its defaults; REBUILD_PATTERN: the same with
`--estimators rebuild` (the rebuild alone). Scores as scenes.py.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prototype import box, read_shot  # noqa: E402
from scenes import Scoring  # noqa: E402


def spread(y, k, pool):
    """Per frame and pixel: v of the quieter side (inf where there is none)."""
    frames = y.shape[0]
    squared = ((y[1:] - y[:-1]) ** 2 / 2).mean(3)  # [g] = between frames g and g + 1
    axes = (0, 1) if pool == 'square' else (1,)  # [row, x, 1]: 3x3, or the 3 pixels of the row
    pooled = np.stack([box(d[..., None], 1, axes)[..., 0] for d in squared])
    sums = np.concatenate([np.zeros((1,) + pooled.shape[1:]), np.cumsum(pooled, 0)])
    v = np.full(y.shape[:3], np.inf)
    for f in range(frames):
        for lo, hi in ((max(0, f - k), f), (f, min(frames - 1, f + k))):
            if hi > lo:
                mean = (sums[hi] - sums[lo]) / (hi - lo)
                v[f] = np.minimum(v[f], mean)
    return v


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    for name in ('noisy', 'ref_a', 'ref_b', 'layer', 'default', 'rebuild'):
        parser.add_argument(name)
    parser.add_argument('--frames', type=int, default=4, help='K: frames on each side (4)')
    parser.add_argument('--z', type=float, nargs='+', default=[6.0])
    parser.add_argument('--pool', choices=('row', 'square'), default='row',
                        help='pixels pooled: the 3 of the row (default) or the 3x3 around')
    parser.add_argument('--transient', help='FIRST-LAST: frames whose changing pixels are scored apart')
    args = parser.parse_args()
    scoring = Scoring(args.noisy, args.ref_a, args.ref_b, args.layer, args.transient)
    noisy = scoring.noisy
    default = read_shot(args.default, args.layer)
    sigma = read_shot(args.default, args.layer + '.sigma')
    rebuilt = read_shot(args.rebuild, args.layer)
    v = spread(noisy, args.frames, args.pool)
    # n inside the image (fewer at its borders and the shot's ends)
    terms = (9 if args.pool == 'square' else 3) * args.frames
    kept = np.all(np.abs(default - rebuilt) < 1e-6, 3)
    distance = (noisy - rebuilt).mean(3)
    print(scoring.line('input', noisy, None))
    print(scoring.line('default', default, sigma))
    for z in args.z:
        limit = np.where(distance < 0, z, np.sqrt(2 * terms) + z)
        taken = kept & (distance ** 2 > limit ** 2 * v)
        out = np.where(taken[..., None], noisy, default)
        out_sigma = np.where(taken[..., None], np.sqrt(v)[..., None], sigma)
        print(scoring.line(f'z {z:g} ({taken.mean() * 100:.2f} % taken)', out, out_sigma))


if __name__ == '__main__':
    main()
