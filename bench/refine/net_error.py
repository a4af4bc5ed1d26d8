#!/usr/bin/python3
# DiffInd relMSE of a `modestack run` directory's denoised and final frames net
# of the reference's own noise (bench/results/refine_gain.md): two references
# of the same scene with different seeds give that noise per pixel as
# (r1 - r2)^2 / 2; it is subtracted from the error against r1. Also the mean
# relMSE sigma predicts. Whole shot and frames 30-36 (switch's crossing).
#   bench/refine/net_error.py RUN_DIR REFERENCE_DIR SECOND_REFERENCE_DIR SCENE
import OpenImageIO as oiio, numpy as np, sys
def rd(f,ch):
    i=oiio.ImageInput.open(f); s=i.spec(); a=i.read_image(0,0,0,s.nchannels,'float').reshape(s.height,s.width,s.nchannels); i.close()
    return np.stack([a[...,s.channelnames.index(c)] for c in ch],-1)
rgb=lambda L:[L+'.R',L+'.G',L+'.B']
run, r1d, r2d, sc = sys.argv[1:5]
N=[];D=[];F=[];S=[]
for t in range(1,49):
    r1=rd(f'{r1d}/{sc}.{t:04d}.exr',rgb('DiffInd')); r2=rd(f'{r2d}/{sc}.{t:04d}.exr',rgb('DiffInd'))
    den=rd(f'{run}/denoised/{sc}.{t:04d}.exr',rgb('DiffInd')); fin=rd(f'{run}/final/{sc}.{t:04d}.exr',rgb('DiffInd'))
    sg=rd(f'{run}/denoised/{sc}.{t:04d}.exr',rgb('DiffInd.sigma'))
    w=r1*r1+0.01
    N.append((((r1-r2)**2/2)/w).mean()); D.append((((den-r1)**2)/w).mean()); F.append((((fin-r1)**2)/w).mean()); S.append((sg*sg/(den*den+0.01)).mean())
N,D,F,S=map(np.array,(N,D,F,S))
for name,sl in [('all',slice(0,48)),('f30-36',slice(29,36))]:
    print(name,'ref noise %.6f  denoised raw %.6f net %.6f  final raw %.6f net %.6f  sigma-predicted %.6f' % (N[sl].mean(), D[sl].mean(), D[sl].mean()-N[sl].mean(), F[sl].mean(), F[sl].mean()-N[sl].mean(), S[sl].mean()))
