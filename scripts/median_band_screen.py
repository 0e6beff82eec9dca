#!/usr/bin/env python3
"""Screen a cost that matches the mean absolute error: would the median
(what an absolute cost aims at) beat the mean (what the squared cost aims
at) of a model's depth residuals, band by band of the read depth? The
screen of docs/results/named-targets.md, "A cost that matches the mean
absolute error".

    python3 scripts/median_band_screen.py PREDICTIONS.csv

PREDICTIONS.csv is `tactrace predict --model MODEL --data PART` (columns
r_mm, true_r_mm, ...). For each band of the read depth: the rows, the
depth MAE, the mean, median and skew of the residual `true - read`, and
the MAE once the band's median is removed. The medians are fitted on the
rows they are scored on, so the last lines are upper bounds: no shift per
band, however fitted, does better on these rows. Needs numpy and scipy.
"""
import sys

import numpy as np
from scipy.stats import skew

EDGES = [-np.inf, -1.75, -1.5, -1.25, -1.0, 0.0, 1.0, np.inf]


def band_rows(pred, edges):
    """(low, high, mask) of each band of the read depth."""
    for lo, hi in zip(edges[:-1], edges[1:]):
        yield lo, hi, (pred >= lo) & (pred < hi)


def with_band_medians(res, pred, edges):
    """|residual| once each band's median (and, apart, its mean) is removed."""
    by_median, by_mean = np.abs(res), np.abs(res)
    for _, _, s in band_rows(pred, edges):
        if s.any():
            by_median[s] = np.abs(res[s] - np.median(res[s]))
            by_mean[s] = np.abs(res[s] - res[s].mean())
    return by_median.mean(), by_mean.mean()


def main(path):
    p = np.genfromtxt(path, delimiter=",", names=True)
    pred, res = p["r_mm"], p["true_r_mm"] - p["r_mm"]
    print(f"all: rows {len(res)} MAE {np.abs(res).mean():.4f} "
          f"mean {res.mean():+.4f} median {np.median(res):+.4f}")
    for lo, hi, s in band_rows(pred, EDGES):
        r, m = res[s], np.median(res[s])
        print(f"read {lo:+5.2f}..{hi:+5.2f} rows {s.sum():3d} MAE {np.abs(r).mean():.4f} "
              f"mean {r.mean():+.4f} median {m:+.4f} skew {skew(r):+.2f} "
              f"-> median removed {np.abs(r - m).mean():.4f}")
    med, mean = with_band_medians(res, pred, EDGES)
    print(f"upper bound, each band's median removed: {med:.4f} (its mean: {mean:.4f})")
    fine = [-np.inf] + list(np.arange(-1.75, 2.0, 0.25)) + [np.inf]
    print(f"upper bound, sixteen bands of 0.25 mm: {with_band_medians(res, pred, fine)[0]:.4f}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
