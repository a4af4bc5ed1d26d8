#!/usr/bin/python3
"""Scores denoised shots of one layer against a reference, counting the
reference's own noise (scenes.sh).

The reference is the mean of two renders with other seeds, A and B; per pixel
n = (A − B)² / 4 estimates the variance of that mean, so that
E[(x − ref)²] = (x − truth)² + n. relMSE = mean((x − ref)² − n) / (ref² + 0.01),
the same denominator as `modestack compare`. Sigma is checked against the error
it should bound plus the reference's noise: ratios of |x − ref| to
sqrt(σ² + n), n there its 3×3 mean (less noisy per pixel; for relMSE the
mean would lend a reference firefly's variance to its dark neighbours).
With one reference (B = none) and --spp NOISY/REF (the two
renders' samples per pixel, independent seeds), the noisy input's own
difference to it gives n: E[(noisy − ref)²] = v_noisy + v_ref and v_noisy =
v_ref·REF/NOISY, so n = box2 over ±2 frames of (noisy − ref)² · NOISY/(NOISY +
REF) (a wider window than two references need, the squares being
heavy-tailed). That assumes the variance falls as 1/spp; a renderer's
quasi-random samples make it fall faster, so this n is an upper bound and the
scores net of it are a lower bound of the error: on the Cycles
orbit_cross_room shot (4 and 512 spp), scored against one of its two
references, it counted 1.6× the DiffInd noise the two references measure
(DiffInd sigma median 1.07 and 3.3 % beyond 3σ, where two references give
1.42 and 8.8 % and n = 0 gives 3.32 and 41 %). Without --spp, n = 0: an
upper bound of the error.

Printed per shot: the noisy input, a 1.5 px Gaussian of it, and each denoised
sequence: relMSE shot-wide, as a multiple of the input's, its worst frame's
multiple, the transient region's (--transient FIRST-LAST: the pixels of those
frames whose reference differs from its temporal median), the share of frames
worse than the input; sigma: RMS(err)/RMS(σ), median(|err|/σ)/0.6745, share
beyond 3σ, recall of the 1 % largest errors in the 10 % largest σ.

  scenes.py NOISY_PATTERN REF_A_PATTERN REF_B_PATTERN|none LAYER DENOISED_PATTERN...
            [--transient FIRST-LAST] [--spp NOISY/REF]
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prototype import box, gauss, read_shot, transient_mask  # noqa: E402


def relative(squared, ref):
    return squared / (ref ** 2 + 0.01)


def score(name, x, sigma, ref, noise, noisy_rel, transient, frames_noisy, pixel_noise):
    e2 = (x - ref) ** 2
    rel = relative(e2 - pixel_noise, ref)
    shot = rel.mean()
    per_frame = rel.mean((1, 2, 3))
    line = (f"  {name:24s} relMSE {shot:.5f} = {shot / noisy_rel.mean():.2f}x input, worst frame "
            f"{(per_frame / frames_noisy).max():.2f}x, frames worse {(per_frame > frames_noisy).mean() * 100:.0f} %")
    if transient is not None:
        line += f", transient {rel[transient].mean() / noisy_rel[transient].mean():.2f}x"
    if sigma is not None:
        total = np.sqrt(sigma ** 2 + noise)
        ratio = np.sqrt(e2) / np.maximum(total, 1e-12)
        top = np.sqrt(e2).ravel() >= np.quantile(np.sqrt(e2), 0.99)
        high = sigma.ravel() >= np.quantile(sigma, 0.90)
        line += (f" | sigma rms {np.sqrt(max((e2 - noise).mean(), 0) / (sigma ** 2).mean()):.2f}, median "
                 f"{np.median(ratio) / 0.6745:.2f}, >3s {(ratio > 3).mean() * 100:.1f} %, recall "
                 f"{(top & high).sum() / top.sum():.2f}")
    return line


class Scoring:
    """One layer's noisy input and reference, read once, and the score of a
    sequence against them (--transient FIRST-LAST: its region scored apart)."""

    def __init__(self, noisy, ref_a, ref_b, layer, transient=None, spp=None):
        self.noisy = read_shot(noisy, layer)
        a = read_shot(ref_a, layer)
        if ref_b != 'none':
            b = read_shot(ref_b, layer)
            self.ref = (a + b) / 2
            # Per pixel, (A − B)²/4 is exact in expectation: relMSE takes it so.
            # Boxed, a reference's firefly would lend its variance to dark
            # neighbours, whose relative error it then swamps (a glossy shot's
            # caustics made relMSE net of the noise negative); sigma's ratios,
            # per pixel, need the boxed estimate's lower noise.
            self.pixel_noise = (a - b) ** 2 / 4
            self.noise = box(self.pixel_noise, 1)
        elif spp:
            noisy_spp, ref_spp = (float(s) for s in spp.split('/'))
            self.ref = a
            self.noise = box((self.noisy - a) ** 2, 2, axes=(0, 1, 2)) * noisy_spp / (noisy_spp + ref_spp)
            self.pixel_noise = self.noise
        else:
            self.ref, self.noise = a, np.zeros_like(a)
            self.pixel_noise = self.noise
        self.transient = None
        if transient:
            first, last = (int(f) for f in transient.split('-'))
            self.transient = transient_mask(self.ref, first, last)
        self.noisy_rel = relative((self.noisy - self.ref) ** 2 - self.pixel_noise, self.ref)
        self.frames_noisy = self.noisy_rel.mean((1, 2, 3))

    def line(self, name, x, sigma):
        return score(name, x, sigma, self.ref, self.noise, self.noisy_rel, self.transient, self.frames_noisy,
                     self.pixel_noise)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('noisy'), parser.add_argument('ref_a'), parser.add_argument('ref_b')
    parser.add_argument('layer'), parser.add_argument('denoised', nargs='+')
    parser.add_argument('--transient', help='FIRST-LAST: frames whose changing pixels are scored apart')
    parser.add_argument('--spp', help='NOISY/REF: with one reference, count its noise from the spp ratio')
    args = parser.parse_args()
    scoring = Scoring(args.noisy, args.ref_a, args.ref_b, args.layer, args.transient, args.spp)
    noisy, ref, noise = scoring.noisy, scoring.ref, scoring.pixel_noise
    print(f"  reference noise: {relative(noise, ref).mean():.5f} relMSE "
          f"({relative(noise, ref).mean() / scoring.noisy_rel.mean() * 100:.1f} % of the input's)")
    print(scoring.line('input', noisy, None))
    print(scoring.line('gauss 1.5 px', gauss(noisy, 1.5)[0], None))
    for pattern in args.denoised:
        x = read_shot(pattern, args.layer)
        try:
            sigma = read_shot(pattern, args.layer + '.sigma')
        except Exception:  # noqa: BLE001 - a run without sigma is scored without it
            sigma = None
        name = pattern.split('/')[-2]
        print(scoring.line(name, x, sigma))


if __name__ == '__main__':
    main()
