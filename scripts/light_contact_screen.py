#!/usr/bin/env python3
"""Screen a light-contact signal the pin vector lacks: do the pins'
apparent sizes in a binarised frame explain what a pin model gets wrong?
The probe of docs/results.md, "A light-contact signal, screened".

    python3 scripts/light_contact_screen.py FRAMES FIT CHOOSE PREDICTIONS.csv

FRAMES is the frames folder the datasets were imported from; FIT and
CHOOSE two imported datasets (the fitted part, the part models are
chosen on); PREDICTIONS.csv is `tactrace predict --model MODEL --data
CHOOSE` of a model fitted on FIT (columns r_mm, true_r_mm, ...). For every
frame, each tracked pin (reference + displacement) is matched to the
white 8-connected component whose centroid is nearest (within 2 px): its
pixel count (area) and second moments (var x - var y, cov xy). Then the
model's depth residual on CHOOSE is regressed on what the model lacks,
out of fold (5-fold, seeded), from: the prediction alone (cubic), and
the prediction with the principal components of the areas (fitted on
FIT), of the moments, of both with the frame's white-pixel count; as a
ridge and as boosted trees. A signal the pins lack lowers the
out-of-fold error below the prediction-alone row. Needs numpy, scipy,
scikit-learn and Pillow. Reads only; prints a table.
"""
import json
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage
from sklearn.decomposition import PCA
from sklearn.ensemble import HistGradientBoostingRegressor
from sklearn.linear_model import RidgeCV
from sklearn.model_selection import KFold, cross_val_predict
from sklearn.preprocessing import StandardScaler

MATCH_PX = 2.0
SEED = 1
SHALLOW_MM = -1.0


def component_stats(image):
    """Centroids (x, y), pixel counts and second moments of the white
    8-connected components of a binarised frame."""
    white = image > 127
    labels, n = ndimage.label(white, structure=np.ones((3, 3), int))
    idx = np.arange(1, n + 1)
    area = ndimage.sum(white, labels, idx)
    cy, cx = np.array(ndimage.center_of_mass(white, labels, idx)).T
    yy, xx = np.indices(white.shape)
    inside = labels > 0
    dx = np.where(inside, xx - cx[labels - 1], 0.0)
    dy = np.where(inside, yy - cy[labels - 1], 0.0)
    moments = np.stack(
        [ndimage.mean(dx * dx - dy * dy, labels, idx), ndimage.mean(dx * dy, labels, idx)], 1
    )
    return np.stack([cx, cy], 1), area, moments, white.sum()


def pin_sizes(frames, dataset):
    """Per frame of DATASET: every pin's area and moments (NaN when no
    component lies within MATCH_PX), and the frame's white-pixel count."""
    x = np.load(os.path.join(dataset, "inputs.npy")).astype(np.float64)
    meta = json.load(open(os.path.join(dataset, "meta.json")))
    ref = np.array(meta["reference_pins"])
    pins = len(ref)
    areas = np.full((len(x), pins), np.nan)
    moments = np.full((len(x), pins, 2), np.nan)
    white = np.zeros(len(x))
    for i, name in enumerate(meta["images"]):
        centres, area, mom, white[i] = component_stats(np.array(Image.open(os.path.join(frames, name))))
        at = ref + np.stack([x[i, :pins], x[i, pins:]], 1)
        dist = np.linalg.norm(at[:, None, :] - centres[None], axis=2)
        nearest = dist.argmin(1)
        ok = dist[np.arange(pins), nearest] < MATCH_PX
        areas[i, ok] = area[nearest[ok]]
        moments[i, ok] = mom[nearest[ok]]
    return areas, moments.reshape(len(x), -1), white


def filled(values, medians):
    values = values.copy()
    missing = np.isnan(values)
    values[missing] = np.take(medians, np.where(missing)[1])
    return values


def components(fit, choose, k):
    """CHOOSE's first k principal components of standardised columns, fitted on FIT."""
    scale = StandardScaler().fit(fit)
    pca = PCA(k, random_state=0).fit(scale.transform(fit))
    return pca.transform(scale.transform(choose))


def main(frames, fit, choose, predictions):
    fa, fm, _ = pin_sizes(frames, fit)
    ca, cm, cw = pin_sizes(frames, choose)
    ca, fa = filled(ca, np.nanmedian(fa, 0)), filled(fa, np.nanmedian(fa, 0))
    cm, fm = filled(cm, np.nanmedian(fm, 0)), filled(fm, np.nanmedian(fm, 0))
    p = np.genfromtxt(predictions, delimiter=",", names=True)
    pred, true = p["r_mm"], p["true_r_mm"]
    residual = pred - true
    base = np.c_[pred, pred**2, pred**3]
    rows = {
        "prediction alone": base,
        "+ areas, 10 PCs": np.c_[base, components(fa, ca, 10)],
        "+ areas, 30 PCs": np.c_[base, components(fa, ca, 30)],
        "+ moments, 20 PCs": np.c_[base, components(fm, cm, 20)],
        "+ both, 40 PCs, white": np.c_[base, components(np.c_[fa, fm], np.c_[ca, cm], 40), cw],
    }
    folds = KFold(5, shuffle=True, random_state=SEED)
    shallow = true < SHALLOW_MM
    print(f"depth MAE as read: {np.abs(residual).mean():.4f} mm, true depth < {SHALLOW_MM} mm: "
          f"{np.abs(residual[shallow]).mean():.4f} mm ({shallow.sum()} rows)")
    for name, x in rows.items():
        x = StandardScaler().fit_transform(x)
        for kind, model in (
            ("ridge", RidgeCV(alphas=np.logspace(-2, 4, 13))),
            ("trees", HistGradientBoostingRegressor(max_iter=200, learning_rate=0.05, max_leaf_nodes=15,
                                                    l2_regularization=1.0, random_state=SEED)),
        ):
            left = residual - cross_val_predict(model, x, residual, cv=folds)
            print(f"{name:22s} {kind}: out of fold {np.abs(left).mean():.4f} mm, "
                  f"shallow {np.abs(left[shallow]).mean():.4f} mm")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
