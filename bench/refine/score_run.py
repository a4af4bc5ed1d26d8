#!/usr/bin/python3
# relMSE of a `modestack run` directory's stages against a reference directory
# (bench/results/refine_gain.md): DiffInd of noisy, denoised and final, and the
# beauty DiffCol*(DiffDir + DiffInd) + Emit of each stage's own passes (noisy
# and final: their Combined), over all 48 frames and over frames 30-36 (the
# crossing of `switch`). Needs Debian's python3-numpy and python3-openimageio.
#   bench/refine/score_run.py RUN_DIR REFERENCE_DIR
import OpenImageIO as oiio, numpy as np, sys, os, glob
run, ref = sys.argv[1], sys.argv[2]
scene = os.path.basename(glob.glob(f'{run}/noisy/*.exr')[0]).split('.')[0]
def rd(f, ch):
    i = oiio.ImageInput.open(f); s = i.spec()
    a = i.read_image(0, 0, 0, s.nchannels, 'float').reshape(s.height, s.width, s.nchannels); i.close()
    return np.stack([a[..., s.channelnames.index(c)] for c in ch], -1)
rgb = lambda L: [f'{L}.R', f'{L}.G', f'{L}.B']
def rel(x, r): return float((((x - r) ** 2) / (r * r + 0.01)).mean())
def beauty(f): 
    p = {L: rd(f, rgb(L)) for L in ['DiffCol', 'DiffDir', 'DiffInd', 'Emit']}
    return p['DiffCol'] * (p['DiffDir'] + p['DiffInd']) + p['Emit']
rows = []
for t in range(1, 49):
    n = lambda k: f'{run}/{k}/{scene}.{t:04d}.exr'
    rf = f'{ref}/{scene}.{t:04d}.exr'
    ri, rb = rd(rf, rgb('DiffInd')), rd(rf, rgb('Combined'))
    rows.append([rel(rd(n('noisy'), rgb('DiffInd')), ri), rel(rd(n('denoised'), rgb('DiffInd')), ri), rel(rd(n('final'), rgb('DiffInd')), ri),
                 rel(rd(n('noisy'), rgb('Combined')), rb), rel(beauty(n('denoised')), rb), rel(rd(n('final'), rgb('Combined')), rb)])
a = np.array(rows); cross = a[29:36]
np.set_printoptions(precision=6, suppress=True)
print(run, 'all   DiffInd noisy/den/final', a[:, :3].mean(0), 'beauty', a[:, 3:].mean(0))
print(run, 'f30-36 DiffInd noisy/den/final', cross[:, :3].mean(0), 'beauty', cross[:, 3:].mean(0))
