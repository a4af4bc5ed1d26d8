#!/usr/bin/python3
"""Prototype of a per-pixel choice among estimators (issue 29), in numpy, on a
shot already denoised by `modestack denoise`. Not a test and not the product: it
measures whether a risk estimate can pick, per pixel, among the temporal rebuild,
the (firefly-clamped) input and Gaussian blurs of it, so that the C++ pass is
built on a rule measured first. Results: bench/results/estimators.md.

  bench/estimators/run.sh   (renders nothing; denoises the Cycles shots and calls this)
  prototype.py NOISY_PATTERN DENOISED_PATTERN REF_PATTERN LAYER [--z Z] [--radius R]

The rule (docs/design.md has the method; this is its first measurement):
  v    noise variance of the clamped input: windowed mean of the squared
       4-neighbour high-pass of (clamped input - rebuild), / 1.25
  SURE risk of estimator f with divergence w at a sample:  (f - y)^2 - v + 2 v w
       (w = h, the rebuild's kept noise; w = centre weight for a Gaussian; the input: v)
  the rebuild is kept unless another estimator's window-mean SURE is lower by more
  than Z standard errors of the window mean of the per-sample difference (a
  significance test: SURE of a strong denoiser is a small difference of large,
  noisy numbers, so the plain argmin picks at random where risks are close)
  sigma^2 = the chosen estimator's known variance part (rebuild: the engine's
  sigma^2; Gaussian: v * sum(w^2); input: v), raised to its windowed SURE where
  that is larger by Z standard errors.
The rebuild's kept noise h is not in the engine's output; this prototype takes it
as a per-layer constant (--kept-noise), which the C++ pass replaces by the exact
per-pixel value the engine already computes for sigma.
"""
import argparse, glob
import numpy as np
import OpenImageIO as oiio


def read_layer(path, layer):
    image = oiio.ImageInput.open(path)
    if image is None:
        raise SystemExit(f"{path}: {oiio.geterror()}")
    spec = image.spec()
    names = list(spec.channelnames)
    wanted = [i for i, n in enumerate(names) if n.rsplit('.', 1)[0] == layer]
    pixels = np.asarray(image.read_image(0, 0, 0, spec.nchannels, 'float'))
    image.close()
    if len(wanted) != 3:
        raise SystemExit(f"{path}: no RGB layer {layer} (channels {names})")
    return pixels[:, :, wanted].astype(np.float64)


def read_shot(pattern, layer):
    files = sorted(glob.glob(pattern))
    if not files:
        raise SystemExit(f"{pattern}: no frames")
    return np.stack([read_layer(f, layer) for f in files])


def box(a, r, axes=(1, 2)):
    """Mean over a (2r+1)-wide window along `axes`, clipped at the edges."""
    out = a
    for ax in axes:
        n = out.shape[ax]
        pad = [(0, 0)] * out.ndim
        pad[ax] = (1, 0)
        c = np.pad(np.cumsum(out, axis=ax), pad)
        idx = np.arange(n)
        hi, lo = np.minimum(idx + r + 1, n), np.maximum(idx - r, 0)
        shape = [1] * out.ndim
        shape[ax] = n
        out = (np.take(c, hi, axis=ax) - np.take(c, lo, axis=ax)) / (hi - lo).reshape(shape)
    return out


def gauss(a, s):
    """Separable Gaussian blur (reflect) of every frame; returns it and the 2D centre weight."""
    r = int(np.ceil(3 * s))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / s) ** 2)
    k /= k.sum()
    out = a
    for ax in (1, 2):
        pad = [(0, 0)] * out.ndim
        pad[ax] = (r, r)
        p = np.pad(out, pad, mode='reflect')
        n = out.shape[ax]
        out = sum(w * np.take(p, np.arange(i, i + n), axis=ax) for i, w in enumerate(k))
    return out, k[r] ** 2, float((k ** 2).sum() ** 2)


def high_pass(a):
    p = np.pad(a, [(0, 0), (1, 1), (1, 1), (0, 0)], mode='reflect')
    return a - 0.25 * (p[:, :-2, 1:-1] + p[:, 2:, 1:-1] + p[:, 1:-1, :-2] + p[:, 1:-1, 2:])


def window_median(a, r):
    """Median over a (2r+1)^2 window and the channels of `a`, per frame."""
    f, h, w, c = a.shape
    p = np.pad(a, [(0, 0), (r, r), (r, r), (0, 0)], mode='reflect')
    stack = np.concatenate([p[:, i:i + h, j:j + w, :] for i in range(2 * r + 1) for j in range(2 * r + 1)], 3)
    return np.median(stack, axis=3, keepdims=True)


def rel(x, ref):
    return (x - ref) ** 2 / (ref ** 2 + 0.01)


def transient_mask(ref, first, last):
    """Pixels of frames first..last (1-based) whose reference differs from its
    temporal median by more than 10 % (+ 0.01): where content changes."""
    median = np.median(ref, axis=0, keepdims=True)
    changed = (np.abs(ref - median) > 0.1 * np.abs(median) + 0.01).any(axis=3, keepdims=True)
    frames = np.zeros((ref.shape[0], 1, 1, 1), dtype=bool)
    frames[first - 1:last] = True
    return np.broadcast_to(changed & frames, ref.shape)


def scores(name, x, sigma, ref, noisy, transient):
    e = x - ref
    per_frame = rel(x, ref).mean((1, 2, 3)) / rel(noisy, ref).mean((1, 2, 3))
    line = (f"{name:8s} relMSE {rel(x, ref).mean():.4f} = {rel(x, ref).mean() / rel(noisy, ref).mean():.2f}x noisy, "
            f"worst frame {per_frame.max():.2f}x")
    if transient is not None:
        line += f", transient {rel(x, ref)[transient].mean():.4f} = " \
                f"{rel(x, ref)[transient].mean() / rel(noisy, ref)[transient].mean():.2f}x"
    if sigma is not None:
        ratio = np.abs(e) / np.maximum(sigma, 1e-12)
        top = np.abs(e).ravel() >= np.quantile(np.abs(e), 0.99)
        high = sigma.ravel() >= np.quantile(sigma, 0.90)
        line += (f" | sigma: rms ratio {np.sqrt((e ** 2).mean() / (sigma ** 2).mean()):.2f}, median ratio "
                 f"{np.median(ratio) / 0.6745:.2f}, beyond 3 sigma {(ratio > 3).mean() * 100:.1f} %, "
                 f"recall {(top & high).sum() / top.sum():.2f}")
    return line


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('noisy'), parser.add_argument('denoised'), parser.add_argument('reference')
    parser.add_argument('layer')
    parser.add_argument('--z', type=float, default=2.0, help='significance of a switch away from the rebuild')
    parser.add_argument('--radius', type=int, default=3, help='risk window radius (3: 7x7)')
    parser.add_argument('--clamp', type=float, default=4.0, help='firefly clamp: 3x3 median + this many noise sd')
    parser.add_argument('--kept-noise', type=float, required=True, help="the rebuild's kept noise h (see above)")
    parser.add_argument('--transient', help='FIRST-LAST: frames whose changing pixels are scored apart')
    args = parser.parse_args()
    y = read_shot(args.noisy, args.layer)
    ref = read_shot(args.reference, args.layer)
    rebuild = read_shot(args.denoised, args.layer)
    engine_sigma = read_shot(args.denoised, args.layer + '.sigma')
    r, z, n = args.radius, args.z, (2 * args.radius + 1) ** 2

    robust_var = window_median(high_pass(y - rebuild) ** 2, r) / 0.4549 / 1.25  # median of chi2(1) = 0.4549
    clamped = np.minimum(y, np.concatenate([window_median(y[..., c:c + 1], 1) for c in range(3)], 3)
                         + args.clamp * np.sqrt(robust_var))
    v = box((high_pass(clamped - rebuild) ** 2).mean(3, keepdims=True) / 1.25, r)

    values, sure, floor = {}, {}, {}
    values['rebuild'] = rebuild
    sure['rebuild'] = ((rebuild - clamped) ** 2 - v + 2 * v * args.kept_noise).mean(3, keepdims=True)
    floor['rebuild'] = (engine_sigma ** 2).mean(3, keepdims=True)
    values['input'], sure['input'], floor['input'] = clamped, v, v
    for s in (1.0, 2.0):
        g, centre, squares = gauss(clamped, s)
        values[f'gauss{s:g}'] = g
        sure[f'gauss{s:g}'] = ((g - clamped) ** 2 - v + 2 * v * centre).mean(3, keepdims=True)
        floor[f'gauss{s:g}'] = v * squares

    names = list(values)
    choice = np.zeros(y.shape[:3] + (1,), dtype=int)
    gain = np.zeros(choice.shape)
    for i, name in enumerate(names[1:], 1):
        d = sure['rebuild'] - sure[name]
        mean = box(d, r)
        se = np.sqrt(np.maximum(box(d * d, r) - mean * mean, 0) / n)
        better = (mean > z * se) & (mean > gain)
        choice[better], gain[better] = i, mean[better]

    def risk(name):
        s = sure[name] * np.ones(choice.shape)
        mean = box(s, r)
        se = np.sqrt(np.maximum(box(s * s, r) - mean * mean, 0) / n)
        return np.where(mean - floor[name] > z * se, mean, floor[name] * np.ones(choice.shape))

    out = np.take_along_axis(np.stack([values[k] for k in names]), np.broadcast_to(choice[None], (1,) + y.shape), 0)[0]
    sigma = np.sqrt(np.maximum(np.take_along_axis(np.stack([risk(k) for k in names]), choice[None], 0)[0], 0))
    sigma = sigma * np.ones(y.shape)
    print(f"{args.layer}: " + ', '.join(f"{k} {(choice == i).mean() * 100:.0f} %" for i, k in enumerate(names)))
    transient = None
    if args.transient:
        first, last = (int(f) for f in args.transient.split('-'))
        transient = transient_mask(ref, first, last)
        print(f"  transient region: {transient[..., 0].sum()} pixels of frames {first}-{last}")
    g15, _, _ = gauss(y, 1.5)
    for name, x, s in [('noisy', y, None), ('clamped', clamped, None), ('gauss1.5', g15, None),
                       ('rebuild', rebuild, engine_sigma), ('chosen', out, sigma)]:
        print('  ' + scores(name, x, s, ref, y, transient))


if __name__ == '__main__':
    main()
