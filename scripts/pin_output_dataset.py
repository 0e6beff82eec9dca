#!/usr/bin/env python3
"""A copy of an imported 127-pin dataset whose pin columns hold a pin
model's prediction instead: the probe of docs/results.md, "Pins and
pixels: leaning on the pins".

    python3 scripts/pin_output_dataset.py DATASET PREDICTIONS.csv OUT

PREDICTIONS.csv is `tactrace predict --model PIN_MODEL --data DATASET`
(columns r_mm, theta_deg, ...). OUT gets an inputs.npy of the dataset's
shape (rows x 254 float32): columns 0 and 1 the predicted r (mm) and
theta (deg), the other 252 zero (the image model's standardiser leaves a
constant column at 0); frames.npy, targets.npy and meta.json are linked
to DATASET's. Plain Python, no numpy.
"""
import csv
import os
import struct
import sys

PIN_VALUES = 254


def main(src, predictions, out):
    rows = list(csv.DictReader(open(predictions)))
    os.makedirs(out)
    for name in ("frames.npy", "targets.npy", "meta.json"):
        os.symlink(os.path.abspath(os.path.join(src, name)), os.path.join(out, name))
    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, %d), }" % (
        len(rows),
        PIN_VALUES,
    )
    header += " " * (63 - (10 + len(header)) % 64) + "\n"
    with open(os.path.join(out, "inputs.npy"), "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode())
        for r in rows:
            values = [float(r["r_mm"]), float(r["theta_deg"])]
            values += [0.0] * (PIN_VALUES - 2)
            f.write(struct.pack("<%df" % PIN_VALUES, *values))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:4])
