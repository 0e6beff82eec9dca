#!/usr/bin/env python3
"""Fresh labelled poses on a straight edge, for `tactrace twin --targets`:
every column drawn uniformly over its range from a recorded seed, in the
columns of the Bristol edge sets (pose_2 = r mm, pose_3 = vertical offset
mm, pose_6 = theta deg, move_1 / move_2 mm and move_6 deg the shear before
the tap). The defaults are the ranges the 127-pin edge set was collected
over (its collection_meta.json: poses_rng, moves_rng). No frames exist for
these rows: image_name only names them (pose_K.png).

    python3 scripts/edge_poses.py --count 4000 --seed 22 > poses.csv
"""
import argparse
import random
import sys

COLUMNS = ["pose_2", "pose_3", "pose_6", "move_1", "move_2", "move_6"]
RANGES = {
    "pose_2": (-5.0, 5.0),
    "pose_3": (-1.0, 1.0),
    "pose_6": (-45.0, 45.0),
    "move_1": (-5.0, 5.0),
    "move_2": (-5.0, 5.0),
    "move_6": (-5.0, 5.0),
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, required=True, help="rows to write")
    parser.add_argument("--seed", type=int, required=True, help="seed of the draws")
    for name in COLUMNS:
        lo, hi = RANGES[name]
        parser.add_argument(f"--{name}", type=float, nargs=2, default=[lo, hi],
                            metavar=("LO", "HI"), help=f"range (default {lo} {hi})")
    args = parser.parse_args()
    if args.count < 1:
        parser.error("--count must be at least 1")
    rng = random.Random(args.seed)
    out = sys.stdout
    out.write("image_name," + ",".join(COLUMNS) + "\n")
    for k in range(args.count):
        values = [rng.uniform(*getattr(args, name)) for name in COLUMNS]
        out.write(f"pose_{k}.png," + ",".join(f"{v:.6f}" for v in values) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
