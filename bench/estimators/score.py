#!/usr/bin/python3
"""Scores denoised shots against a reference (relMSE shot-wide, worst frame and
transient region as multiples of the noisy input; sigma's calibration), with
the functions of prototype.py.

  score.py NOISY_PATTERN REF_PATTERN LAYER DENOISED_PATTERN... [--transient FIRST-LAST]
"""
import argparse
from prototype import read_shot, scores, transient_mask

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument('noisy'), parser.add_argument('reference'), parser.add_argument('layer')
parser.add_argument('denoised', nargs='+')
parser.add_argument('--transient', help='FIRST-LAST: frames whose changing pixels are scored apart')
args = parser.parse_args()
noisy = read_shot(args.noisy, args.layer)
reference = read_shot(args.reference, args.layer)
transient = None
if args.transient:
    first, last = (int(f) for f in args.transient.split('-'))
    transient = transient_mask(reference, first, last)
for pattern in args.denoised:
    values = read_shot(pattern, args.layer)
    sigma = read_shot(pattern, args.layer + '.sigma')
    print('  ' + scores(pattern.split('/')[-2][:8], values, sigma, reference, noisy, transient))
