#!/usr/bin/env python3
"""Screen the pins' shapes as a depth signal: does a simple model of the
depth from the pins' displacements and each pin's shape beat the same
model on the displacements alone? Issue 21; docs/results/named-targets.md,
"The pins' shapes as inputs, screened".

    python3 scripts/pin_shape_screen.py FRAMES FIT CHOOSE [--target K] [--band K MIN MAX]

FRAMES is the frames folder two imported datasets came from: FIT (where
everything is fitted) and CHOOSE (where the errors are measured; never
fitted on). `--target K`: the column of targets.npy modelled (default 0,
the depth `pose_2` in the surface import); a circular target (meta.json's
`target_circular`, degrees) is fitted as its sine and cosine and its
error wrapped. `--band K MIN MAX`: the rows of CHOOSE whose column K lies
in [MIN, MAX) are reported apart too (default 0 -inf -1: the surface's
taps shallower than -1 mm; the 331-pin edge's rim: 0 5 inf). In every frame each tracked pin
(reference + displacement) is matched to the white 8-connected component
whose centroid is nearest, within 2 px; the pin's shape is that
component's pixel count (area) and its normalised second central
moments, e = (mu20 - mu02) / (mu20 + mu02) and f = 2 mu11 / (mu20 +
mu02) (elongation along the image axes and along the diagonals: a
round blob has e = f = 0, and sqrt(e^2 + f^2) is its eccentricity
measure, atan2(f, e) / 2 its orientation). Unmatched pins take the fit
part's median. Then the target is fitted on FIT from 35 principal components
of the standardised displacements, alone or with principal components of
the shapes (areas 10, moments 20, all three 30), by a ridge (alpha by
RidgeCV on FIT) and by a small MLP (256 ReLU units, Adam, seed 1), and
the mean absolute error on CHOOSE is printed, overall and in the band. Needs numpy, scipy, scikit-learn, Pillow. Reads only.
"""
import argparse
import json
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage
from scipy.spatial import cKDTree
from sklearn.decomposition import PCA
from sklearn.linear_model import RidgeCV
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

MATCH_PX = 2.0
SEED = 1
PIN_COMPONENTS = 35
SHAPE_VARIANTS = {"areas, 10 PCs": ([0], 10), "moments, 20 PCs": ([1, 2], 20), "all three, 30 PCs": ([0, 1, 2], 30)}


def blob_shapes(image):
    """Centroids (n x 2, x y), areas and normalised moments (e, f) of
    the white 8-connected components of a binarised frame, by sums of
    pixel coordinates per label."""
    labels, n = ndimage.label(image > 127, structure=np.ones((3, 3), int))
    lab = labels.ravel()
    keep = lab > 0
    lab = lab[keep] - 1
    ys, xs = np.indices(labels.shape)
    xs, ys = xs.ravel()[keep].astype(float), ys.ravel()[keep].astype(float)

    def total(v):
        return np.bincount(lab, weights=v, minlength=n)

    area = np.bincount(lab, minlength=n).astype(float)
    cx, cy = total(xs) / area, total(ys) / area
    mu20 = total(xs * xs) / area - cx * cx
    mu02 = total(ys * ys) / area - cy * cy
    mu11 = total(xs * ys) / area - cx * cy
    spread = np.maximum(mu20 + mu02, 1e-9)
    return np.c_[cx, cy], np.c_[area, (mu20 - mu02) / spread, 2 * mu11 / spread]


def pin_shapes(frames, dataset):
    """N x P x 3 shapes of DATASET's tracked pins (NaN where unmatched)
    and the fraction matched."""
    x = np.load(os.path.join(dataset, "inputs.npy")).astype(float)
    meta = json.load(open(os.path.join(dataset, "meta.json")))
    ref = np.asarray(meta["reference_pins"], float)
    pins = len(ref)
    out = np.full((len(x), pins, 3), np.nan)
    for i, name in enumerate(meta["images"]):
        centres, shapes = blob_shapes(np.asarray(Image.open(os.path.join(frames, name)).convert("L")))
        where = ref + np.c_[x[i, :pins], x[i, pins:]]
        dist, nearest = cKDTree(centres).query(where)
        hit = dist < MATCH_PX
        out[i, hit] = shapes[nearest[hit]]
    return out, np.isfinite(out[..., 0]).mean()


def with_fit_medians(values, medians):
    missing = np.isnan(values)
    return np.where(missing, medians[np.newaxis], values)


def block_components(fit, other, k):
    """k principal components of standardised columns, fitted on FIT."""
    reduce = make_pipeline(StandardScaler(), PCA(k, random_state=0)).fit(fit)
    return reduce.transform(fit), reduce.transform(other)


def models():
    alphas = np.logspace(-3, 4, 15)
    return {
        "ridge": lambda: make_pipeline(StandardScaler(), RidgeCV(alphas=alphas)),
        "mlp": lambda: make_pipeline(
            StandardScaler(),
            MLPRegressor(hidden_layer_sizes=(256,), alpha=1e-4, learning_rate_init=1e-3, max_iter=400, early_stopping=False,
                         random_state=SEED),
        ),
    }


def fitted_error(model, f, c, y_fit, y_choose, circular):
    """|prediction - truth| on CHOOSE; a circular target (deg) through
    its sine and cosine, the error wrapped to [0, 180]."""
    if not circular:
        return np.abs(model.fit(f, y_fit).predict(c) - y_choose)
    rad = np.radians(y_fit)
    sc = model.fit(f, np.c_[np.sin(rad), np.cos(rad)]).predict(c)
    diff = np.degrees(np.arctan2(sc[:, 0], sc[:, 1])) - y_choose
    return np.abs((diff + 180.0) % 360.0 - 180.0)


def main(a):
    meta = json.load(open(os.path.join(a.fit, "meta.json")))
    circular = bool(meta.get("target_circular", [False] * (a.target + 1))[a.target])
    t_fit, t_choose = (np.load(os.path.join(d, "targets.npy")).astype(float) for d in (a.fit, a.choose))
    y_fit, y_choose = t_fit[:, a.target], t_choose[:, a.target]
    pins = [np.load(os.path.join(d, "inputs.npy")).astype(float) for d in (a.fit, a.choose)]
    pin_fit, pin_choose = block_components(pins[0], pins[1], PIN_COMPONENTS)
    (s_fit, m_fit), (s_choose, m_choose) = pin_shapes(a.frames, a.fit), pin_shapes(a.frames, a.choose)
    medians = np.nanmedian(s_fit, axis=0)
    s_fit, s_choose = with_fit_medians(s_fit, medians), with_fit_medians(s_choose, medians)
    column, low, high = a.band
    band = (t_choose[:, int(column)] >= low) & (t_choose[:, int(column)] < high)
    depth = t_fit[:, int(column)]
    print(f"target {meta['target_names'][a.target]} (circular: {circular}); pins matched to a component: "
          f"fit {m_fit:.4f}, choose {m_choose:.4f}; choose rows {len(y_choose)}, in the band: {band.sum()}")
    print(f"mean area {np.nanmean(s_fit[..., 0]):.2f} px; on fit, the frame's mean area vs column {int(column)}: "
          f"r = {np.corrcoef(s_fit[..., 0].mean(1), depth)[0, 1]:+.3f}; its mean eccentricity: "
          f"r = {np.corrcoef(np.hypot(s_fit[..., 1], s_fit[..., 2]).mean(1), depth)[0, 1]:+.3f}")
    inputs = {"pins alone": (pin_fit, pin_choose)}
    for name, (measures, k) in SHAPE_VARIANTS.items():
        f, c = (s[:, :, measures].reshape(len(s), -1) for s in (s_fit, s_choose))
        f, c = block_components(f, c, k)
        inputs["pins + " + name] = (np.c_[pin_fit, f], np.c_[pin_choose, c])
    for kind, make in models().items():
        for name, (f, c) in inputs.items():
            error = fitted_error(make(), f, c, y_fit, y_choose, circular)
            print(f"{kind:5s} {name:28s} MAE on choose {error.mean():.4f}, in the band {error[band].mean():.4f}")


def arguments():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("frames")
    p.add_argument("fit")
    p.add_argument("choose")
    p.add_argument("--target", type=int, default=0)
    p.add_argument("--band", type=float, nargs=3, default=[0, -np.inf, -1.0], metavar=("K", "MIN", "MAX"))
    return p.parse_args()


if __name__ == "__main__":
    main(arguments())
