#!/usr/bin/python3
"""Sigma's calibration where the truth is known exactly: a synthetic shot made
of three spatial modes (a gradient with a hard edge, a lit lobe with an edge, a
box) times smooth temporal weights, plus white Gaussian noise whose standard
deviation grows with the signal (0.15·sqrt(signal) + 0.02, shot-noise-like).
The noise is independent in every pixel, channel and frame and has no tails, so
what is left of sigma's miscalibration here is the estimator's own, not the
renderer's (issue 29; bench/results/estimators.md). Not a test.

  sigma_synthetic.py MODESTACK WORK [--seed S] [--run NAME OPTIONS...]...

Each --run denoises the shot with `modestack denoise` and OPTIONS (one string)
and prints RMS(err)/RMS(sigma), median(|err|/sigma)/0.6745 and the share of
|err| > 3 sigma (a calibrated Gaussian error bar: 1, 1, 0.27 %). Without --run:
the default, the rebuild alone, and the rebuild without the mode filter at the
shot's rank 3. Environment variables of the caller reach modestack.
Needs /usr/bin/python3 with Debian's python3-numpy and python3-openimageio.
"""
import argparse
import glob
import os
import subprocess

import numpy as np
import OpenImageIO as oiio

HEIGHT, WIDTH, FRAMES = 96, 128, 48


def make_shot(directory, seed):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:HEIGHT, 0:WIDTH] / np.array([HEIGHT, WIDTH])[:, None, None]
    modes = [0.5 + 0.4 * xx + 0.3 * (yy > 0.5),
             np.exp(-((xx - 0.3) ** 2 + (yy - 0.4) ** 2) / 0.02) * (xx > 0.25),
             ((xx > 0.6) & (xx < 0.8) & (yy > 0.2) & (yy < 0.6)) * 0.5]
    t = np.arange(FRAMES) / FRAMES
    weights = [np.ones(FRAMES), 0.5 + 0.5 * np.sin(2 * np.pi * t), 0.5 + 0.5 * np.cos(3 * np.pi * t)]
    colours = [np.array([1, 0.8, 0.6]), np.array([0.3, 0.5, 1.0]), np.array([0.9, 0.2, 0.2])]
    signal = sum(w[:, None, None, None] * m[None, :, :, None] * c[None, None, None, :]
                 for w, m, c in zip(weights, modes, colours))
    noise = rng.standard_normal(signal.shape) * (0.15 * np.sqrt(signal) + 0.02)
    for name, shot in (('clean', signal), ('noisy', signal + noise)):
        os.makedirs(os.path.join(directory, name), exist_ok=True)
        for f in range(FRAMES):
            path = os.path.join(directory, name, f'f.{f + 1:04d}.exr')
            spec = oiio.ImageSpec(WIDTH, HEIGHT, 3, oiio.FLOAT)
            out = oiio.ImageOutput.create(path)
            out.open(path, spec)
            out.write_image(shot[f].astype(np.float32))
            out.close()


def read(pattern, names):
    frames = []
    for path in sorted(glob.glob(pattern)):
        image = oiio.ImageBuf(path)
        channels = image.spec().channelnames
        frames.append(image.get_pixels(oiio.FLOAT)[..., [channels.index(n) for n in names]])
    return np.stack(frames)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('modestack'), parser.add_argument('work')
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--run', nargs=2, action='append', metavar=('NAME', 'OPTIONS'))
    args = parser.parse_args()
    runs = args.run or [('default', ''), ('rebuild', '--estimators rebuild'),
                        ('no-mode-filter', '--estimators rebuild --no-mode-filter --rank 3')]
    make_shot(args.work, args.seed)
    truth = read(os.path.join(args.work, 'clean', 'f.*.exr'), ['R', 'G', 'B'])
    for name, options in runs:
        out = os.path.join(args.work, name)
        subprocess.run([args.modestack, 'denoise', os.path.join(args.work, 'noisy', 'f.####.exr'), '-o',
                        os.path.join(out, 'f.####.exr'), '-q'] + options.split(), check=True)
        value = read(os.path.join(out, 'f.*.exr'), ['R', 'G', 'B'])
        sigma = read(os.path.join(out, 'f.*.exr'), ['sigma.R', 'sigma.G', 'sigma.B'])
        error = value - truth
        ratio = np.abs(error) / np.maximum(sigma, 1e-12)
        print(f'{name:16s} RMS ratio {np.sqrt((error ** 2).mean() / (sigma ** 2).mean()):.2f}, median ratio '
              f'{np.median(ratio) / 0.6745:.2f}, beyond 3 sigma {(ratio > 3).mean() * 100:.2f} %, '
              f'relMSE {((error ** 2) / (truth ** 2 + 0.01)).mean():.6f}')


if __name__ == '__main__':
    main()
