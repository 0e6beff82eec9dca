#!/usr/bin/env python3
"""Screen canonical turns for an edge over the full circle: would a net that
sees every tap turned to one edge direction read the angle better? The
screen of docs/results/any-tactip.md, "The 331-pin edge: canonical turns,
screened".

    python3 scripts/canonical_turn_screen.py make FIT OUT [--copies 6]
        [--seed 0] [--wide-share 0.3] [--wide 20] [--sd 4]
    python3 scripts/canonical_turn_screen.py refine MODEL DATA START.csv
        [--turns 3] [--offsets 0] [--tactrace target/release/tactrace]
    python3 scripts/canonical_turn_screen.py roundtrip DATA [--angle 10]

A tap's field is turned by an angle phi about the centre of its reference
pins: pin i takes the displacement the field has at the centre plus the
pin's offset turned by phi (barycentric interpolation on the Delaunay
triangles of the reference pins; the nearest pin outside them), and the
vector is turned back by -phi. Turning by phi = -theta brings every edge
of these sets to one direction (the angle's sign is the turned copies'
`angle_sign = -1`), so after a turn by -(theta - eps) the edge lies at eps.

`make` writes a dataset of COPIES turns of every row of FIT, each turned
to the true angle less a draw eps (a share `--wide-share` uniform within
`--wide` deg, the rest normal with `--sd` deg), with eps as the angle
target: the training set of a net that reads what is left of the angle
once a tap is turned near its edge. `refine` starts from the angles a
first model read (START.csv: `tactrace predict` of DATA), turns each tap
by the reading, lets MODEL (fitted on `make`'s output) read what is left,
adds it, and repeats; it prints the errors after each turn, by band of the
edge distance. `roundtrip` turns DATA's fields by an angle and back and
prints what the interpolation lost. Needs numpy and scipy.
"""
import argparse
import io
import json
import os
import subprocess
import tempfile

import numpy as np
from scipy.spatial import Delaunay, cKDTree


def wrap(deg):
    """An angle difference in [-180, 180) deg."""
    return (deg + 180.0) % 360.0 - 180.0


def load(folder):
    """meta.json, inputs (N x 2P px), targets (N x T) and reference pins."""
    with open(os.path.join(folder, "meta.json")) as f:
        meta = json.load(f)
    inputs = np.load(os.path.join(folder, "inputs.npy")).astype(np.float64)
    targets = np.load(os.path.join(folder, "targets.npy")).astype(np.float64)
    return meta, inputs, targets, np.asarray(meta["reference_pins"], float)


def save(like, folder, inputs, targets, images):
    """A dataset folder with `like`'s meta.json, these rows and images."""
    with open(os.path.join(like, "meta.json")) as f:
        meta = json.load(f)
    meta["samples"] = int(len(inputs))
    meta["images"] = images
    meta["origin"] = meta.get("origin", "") + " (canonical turns, screen)"
    os.makedirs(folder)
    with open(os.path.join(folder, "meta.json"), "w") as f:
        json.dump(meta, f)
    np.save(os.path.join(folder, "inputs.npy"), inputs.astype(np.float32))
    np.save(os.path.join(folder, "targets.npy"), targets.astype(np.float32))


class Turner:
    """Turns pin displacement fields about the reference pins' centre."""

    def __init__(self, reference):
        self.reference = reference
        self.centre = reference.mean(axis=0)
        self.triangles = Delaunay(reference)
        self.tree = cKDTree(reference)

    def sample_points(self, phi_deg):
        """Where each row's pins read the field: N*P x 2 px."""
        rel = self.reference - self.centre
        phi = np.radians(phi_deg)[:, None]
        c, s = np.cos(phi), np.sin(phi)
        x = self.centre[0] + c * rel[:, 0] - s * rel[:, 1]
        y = self.centre[1] + s * rel[:, 0] + c * rel[:, 1]
        return np.stack([x.ravel(), y.ravel()], axis=1)

    def weights(self, points):
        """Vertices and barycentric weights of each point (N*P x 3)."""
        simplex = self.triangles.find_simplex(points)
        inside = simplex >= 0
        verts = np.zeros((len(points), 3), dtype=np.int64)
        bary = np.zeros((len(points), 3))
        tf = self.triangles.transform[simplex[inside]]
        b = np.einsum("ijk,ik->ij", tf[:, :2, :], points[inside] - tf[:, 2, :])
        bary[inside] = np.concatenate([b, 1.0 - b.sum(axis=1, keepdims=True)], 1)
        verts[inside] = self.triangles.simplices[simplex[inside]]
        verts[~inside] = self.tree.query(points[~inside])[1][:, None]
        bary[~inside] = [1.0, 0.0, 0.0]
        return verts, bary

    def turn(self, inputs, phi_deg):
        """Each row's field turned by its phi (deg): N x 2P px."""
        n, p = len(inputs), len(self.reference)
        verts, bary = self.weights(self.sample_points(phi_deg))
        rows = np.repeat(np.arange(n), p)[:, None]
        dx = (inputs[:, :p][rows, verts] * bary).sum(1).reshape(n, p)
        dy = (inputs[:, p:][rows, verts] * bary).sum(1).reshape(n, p)
        phi = np.radians(phi_deg)[:, None]
        c, s = np.cos(phi), np.sin(phi)
        return np.concatenate([c * dx + s * dy, -s * dx + c * dy], axis=1)


def make(args):
    meta, inputs, targets, reference = load(args.fit)
    turner = Turner(reference)
    rng = np.random.default_rng(args.seed)
    n = len(inputs)
    fields, labels = [], []
    for _ in range(args.copies):
        wide = rng.random(n) < args.wide_share
        eps = np.where(wide, rng.uniform(-args.wide, args.wide, n), rng.normal(0, args.sd, n))
        fields.append(turner.turn(inputs, -(targets[:, 1] - eps)))
        labels.append(np.stack([targets[:, 0], wrap(eps)], axis=1))
    images = list(meta.get("images", [])) * args.copies
    save(args.fit, args.out, np.concatenate(fields), np.concatenate(labels), images)
    print(f"wrote {args.out}: {n * args.copies} rows, {args.copies} turns of each of {n}")


def read(tactrace, model, like, inputs, images):
    """`tactrace predict` of these rows: N x (reads, truths) array."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = os.path.join(tmp, "turned")
        save(like, folder, inputs, np.zeros((len(inputs), 2)), images)
        out = subprocess.run([tactrace, "predict", "--model", model, "--data", folder],
                             capture_output=True, text=True, check=True).stdout
    return np.loadtxt(io.StringIO(out), delimiter=",", skiprows=1)


def report(tag, targets, r, theta):
    mm = np.abs(r - targets[:, 0]).mean()
    err = np.abs(wrap(theta - targets[:, 1]))
    d = targets[:, 0]
    bands = [(d < -3), (d >= -3) & (d < 3), (d >= 3) & (d < 5), (d >= 5)]
    text = ", ".join(f"{err[b].mean():.2f}" for b in bands)
    print(f"{tag}: {mm:.4f} mm {err.mean():.3f} deg, sum over 0.20 mm and 2.5 deg "
          f"{mm / 0.2 + err.mean() / 2.5:.4f}; angle by r < -3 / -3..3 / 3..5 / >= 5 mm: {text}")


def refine(args):
    meta, inputs, targets, reference = load(args.data)
    start = np.loadtxt(args.start, delimiter=",", skiprows=1)
    if not np.allclose(start[:, 3], targets[:, 1], atol=1e-3):
        raise SystemExit(f"{args.start} is not a prediction of {args.data} (its true angles differ)")
    turner = Turner(reference)
    images = list(meta.get("images", []))
    r0, theta = start[:, 0], start[:, 1]
    report("the first model", targets, r0, theta)
    offsets = [float(a) for a in args.offsets.split(",")]
    for k in range(args.turns):
        reads = [read(args.tactrace, args.model, args.data, turner.turn(inputs, -(theta + o)), images)
                 for o in offsets]
        left = [np.radians(a[:, 1] + o) for a, o in zip(reads, offsets)]
        theta = wrap(theta + np.degrees(np.arctan2(np.mean(np.sin(left), 0), np.mean(np.cos(left), 0))))
        r = np.mean([a[:, 0] for a in reads], axis=0)
        report(f"turn {k + 1}, its distance", targets, r, theta)
        report(f"turn {k + 1}, the first model's distance", targets, r0, theta)


def roundtrip(args):
    _, inputs, _, reference = load(args.data)
    turner = Turner(reference)
    n = min(len(inputs), 500)
    x = inputs[:n]
    back = turner.turn(turner.turn(x, np.full(n, args.angle)), np.full(n, -args.angle))
    spread = x - x.mean(axis=1, keepdims=True)
    lost = np.linalg.norm(back - x) / np.linalg.norm(spread)
    print(f"turned by {args.angle} deg and back: {lost:.3f} of the fields' spread lost ({n} rows)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make")
    m.add_argument("fit")
    m.add_argument("out")
    m.add_argument("--copies", type=int, default=6)
    m.add_argument("--seed", type=int, default=0)
    m.add_argument("--wide-share", type=float, default=0.3)
    m.add_argument("--wide", type=float, default=20.0)
    m.add_argument("--sd", type=float, default=4.0)
    r = sub.add_parser("refine")
    r.add_argument("model")
    r.add_argument("data")
    r.add_argument("start")
    r.add_argument("--turns", type=int, default=3)
    r.add_argument("--offsets", default="0")
    r.add_argument("--tactrace", default="target/release/tactrace")
    t = sub.add_parser("roundtrip")
    t.add_argument("data")
    t.add_argument("--angle", type=float, default=10.0)
    args = parser.parse_args()
    if getattr(args, "out", None) and os.path.exists(args.out):
        raise SystemExit(f"{args.out} exists: choose another folder")
    {"make": make, "refine": refine, "roundtrip": roundtrip}[args.command](args)


if __name__ == "__main__":
    main()
