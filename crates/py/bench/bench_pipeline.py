"""Frame -> prediction in plain Python, the pipeline tactrace replaces
(docs/results.md, "Speed"): OpenCV's SimpleBlobDetector with the `real256`
preset, the pins put in reference order by the Hungarian method
(scipy.optimize.linear_sum_assignment on squared distances), then the pose
model's prediction in numpy from its stored weights (standardise, project
onto the principal components, each net's layers with sigmoid hidden
units). It does not use the tactrace package. Usage:

    python crates/py/bench/bench_pipeline.py \
        --model runs/reproduce/models/pdennn \
        --real-frames ../shared/data/tactip127-edge2d/frames --frames 2000

Needs numpy, scipy and opencv-python-headless. The frames are the first
`--frames` `.png` files of the folder in sorted order without `init_0.png`
(the reference), the ones `tactrace bench --real-frames DIR --taps N`
times. Prints per-frame wall-clock times (median and 95th percentile, one
thread) of detection, ordering and prediction, their sum, and the
prediction of a whole batch per sample.
"""

import argparse
import json
import struct
import time
from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment


def detector():
    """SimpleBlobDetector with tactrace's `real256` preset."""
    p = cv2.SimpleBlobDetector_Params()
    p.minThreshold, p.maxThreshold, p.thresholdStep = 82.39, 215.98, 10.0
    p.minDistBetweenBlobs, p.minRepeatability = 4.0, 2
    p.filterByColor, p.blobColor = True, 255
    p.filterByArea, p.minArea, p.maxArea = True, 5.0, 70.0
    p.filterByCircularity, p.minCircularity = True, 0.5
    p.filterByInertia, p.minInertiaRatio = True, 0.3
    p.filterByConvexity, p.minConvexity = True, 0.8
    return cv2.SimpleBlobDetector_create(p)


def safetensors(path):
    """The arrays of a safetensors file, by name."""
    raw = path.read_bytes()
    (n,) = struct.unpack("<Q", raw[:8])
    header = json.loads(raw[8 : 8 + n])
    out = {}
    for name, t in header.items():
        if name == "__metadata__":
            continue
        a, b = t["data_offsets"]
        out[name] = np.frombuffer(raw[8 + n + a : 8 + n + b], dtype=np.float32).reshape(t["shape"])
    return out


class Model:
    """A tactrace pose model's prediction in numpy (f64 up to the nets'
    inputs, f32 in the nets, as tactrace computes it)."""

    def __init__(self, folder):
        m = json.loads((folder / "model.json").read_text())
        w = safetensors(folder / "weights.safetensors")
        self.mean = np.asarray(m["standardiser"]["mean"])
        self.std = np.asarray(m["standardiser"]["std"])
        self.y_mean = np.asarray(m["target_scaling"]["mean"])
        self.y_std = np.asarray(m["target_scaling"]["std"])
        self.nets = []
        for k, net in enumerate(m["nets"]):
            pca = net.get("pca")
            proj = None
            if pca:
                comps = np.asarray(pca["components"]).reshape(len(pca["scales"]), -1)
                proj = (np.asarray(pca["mean"]), comps, np.asarray(pca["scales"]))
            depth = len(net["sizes"]) - 1
            layers = [(w[f"net{k}.W{l}"], w[f"net{k}.b{l}"]) for l in range(1, depth + 1)]
            self.nets.append((net["targets"], proj, layers))

    def predict(self, x):
        """Rows of displacement vectors -> rows of [r mm, theta deg]."""
        z = (np.atleast_2d(x).astype(np.float64) - self.mean) / self.std
        out = np.zeros((z.shape[0], 2))
        for targets, proj, layers in self.nets:
            u = z if proj is None else ((z - proj[0]) @ proj[1].T) * proj[2]
            s = u.astype(np.float32)
            for i, (w, b) in enumerate(layers):
                s = s @ w + b
                if i + 1 < len(layers):
                    s = 1.0 / (1.0 + np.exp(-s))
            out[:, targets] = s
        return out * self.y_std + self.y_mean


def order(reference, points):
    """Pins in reference order: the Hungarian assignment of reference pins
    to points on squared distance (a missing pin stays at rest)."""
    cost = ((reference[:, None, :] - points[None, :, :]) ** 2).sum(-1)
    rows, cols = linear_sum_assignment(cost)
    pins = reference.copy()
    pins[rows] = points[cols]
    return pins


def stats(us):
    us = np.sort(np.asarray(us))
    p95 = us[max(int(np.ceil(0.95 * len(us))), 1) - 1]
    return f"median {np.median(us):7.1f} us, p95 {p95:7.1f} us"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, type=Path)
    ap.add_argument("--real-frames", required=True, type=Path)
    ap.add_argument("--frames", type=int, default=2000)
    a = ap.parse_args()
    cv2.setNumThreads(1)
    model = Model(a.model)
    det = detector()
    ref_img = cv2.imread(str(a.real_frames / "init_0.png"), cv2.IMREAD_GRAYSCALE)
    reference = np.array([k.pt for k in det.detect(ref_img)])
    paths = sorted(p for p in a.real_frames.glob("*.png") if p.name != "init_0.png")
    images = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in paths[: a.frames]]
    t_det, t_ord, t_pred, t_all, rows, counts = [], [], [], [], [], []
    for img in images:
        t0 = time.perf_counter()
        kps = det.detect(img)
        t1 = time.perf_counter()
        pins = order(reference, np.array([k.pt for k in kps]).reshape(-1, 2))
        d = pins - reference
        x = np.concatenate([d[:, 0], d[:, 1]])
        t2 = time.perf_counter()
        model.predict(x)
        t3 = time.perf_counter()
        t_det.append((t1 - t0) * 1e6)
        t_ord.append((t2 - t1) * 1e6)
        t_pred.append((t3 - t2) * 1e6)
        t_all.append((t3 - t0) * 1e6)
        rows.append(x)
        counts.append(len(kps))
    batch = np.array(rows)
    best = min(
        (lambda t0: (model.predict(batch), time.perf_counter() - t0)[1])(time.perf_counter())
        for _ in range(5)
    )
    print(f"{len(images)} frames, {len(reference)} reference pins, "
          f"{sum(c == len(reference) for c in counts)} frames with that many blobs")
    print(f"detect (cv2 SimpleBlobDetector): {stats(t_det)}")
    print(f"order (scipy Hungarian):         {stats(t_ord)}")
    print(f"predict one row (numpy):         {stats(t_pred)}")
    print(f"frame -> prediction:             {stats(t_all)}")
    print(f"predict a batch of {len(batch)} (numpy): {best * 1e6 / len(batch):.2f} us a row")


if __name__ == "__main__":
    main()
