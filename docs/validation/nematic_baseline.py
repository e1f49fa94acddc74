#!/usr/bin/env python3
"""The nematic order Q00^2 of n randomly oriented grains: the value below which no sample of n
grains can read as ordered (docs/pinacoids-and-the-paper.md, "The nematic order and the size of
the sample"). The formula is docs/model.md's ("Nematic order"): for each body axis u, v, w the
tensor Q = (1/n) sum (3/2 a a^T - 1/2 I); Q00^2 is the largest eigenvalue of the three tensors.

Usage: python3 docs/validation/nematic_baseline.py [N ...]   (default 40 100 250 1000 3000)
Prints one Markdown row per n: the mean and standard deviation over 200 samples, and the mean
times sqrt(n).
"""
import sys

import numpy as np


def q00(rotations):
    n = rotations.shape[0]
    best = -1.0
    for axis in range(3):
        a = rotations[:, :, axis]
        q = 1.5 * np.einsum("ni,nj->ij", a, a) / n - 0.5 * np.eye(3)
        best = max(best, np.linalg.eigvalsh(q)[-1])
    return best


def main():
    sizes = [int(a) for a in sys.argv[1:]] or [40, 100, 250, 1000, 3000]
    rng = np.random.default_rng(1)
    print("| grains n | Q00^2, random (mean ± sd of 200) | mean x sqrt(n) |\n|---|---|---|")
    for n in sizes:
        # Random rotations: the Q factor of a Gaussian matrix is uniform up to the signs of its
        # columns, which a a^T does not see.
        values = [q00(np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]) for _ in range(200)]
        mean, sd = float(np.mean(values)), float(np.std(values))
        print(f"| {n:,} | {mean:.3f} ± {sd:.3f} | {mean * np.sqrt(n):.2f} |")


if __name__ == "__main__":
    main()
