"""tactrace from Python, notebook style: real TacTip frames -> a pose model
-> predictions, a simulated tap, and the flower followed round.

Install the package first (from the repository root):

    pip install ./crates/py

and run with the real edge set beside the repository (README, "The real
TacTip data") or named by TACTRACE_REAL_DATA:

    python examples/python_real_frames.py [--limit 1500] [--epochs 40]

The frames are imported in Python (read_frame + PinExtractor), which gives
the vectors `tactrace import` writes. With matplotlib installed it saves
predicted-vs-true plots and the followed trajectory as PNGs in --out.
"""

import argparse
import csv
import os
import time
from pathlib import Path

import numpy as np

import tactrace

# %% Arguments and data
ap = argparse.ArgumentParser(description="Train on real TacTip frames from Python")
default_data = Path(__file__).resolve().parents[1].parent / "shared/data/tactip127-edge2d"
ap.add_argument("--data", type=Path,
                default=Path(os.environ.get("TACTRACE_REAL_DATA", default_data)))
ap.add_argument("--limit", type=int, default=1500, help="frames to use (0: all)")
ap.add_argument("--epochs", type=int, default=40)
ap.add_argument("--out", type=Path, default=Path("runs/python_example"))
args = ap.parse_args()
frames_dir = args.data / "frames"

# %% Extract every frame's pin displacements (254 values: x then y, px)
extractor = tactrace.PinExtractor(frames_dir / "init_0.png")  # the real256 preset
with open(args.data / "targets.csv") as f:
    rows = list(csv.DictReader(f))
if args.limit:
    rows = rows[:args.limit]
t0 = time.perf_counter()
inputs, targets = [], []
for row in rows:
    try:
        d = extractor.displacement(tactrace.read_frame(frames_dir / row["image_name"]))
    except tactrace.InputError as e:  # too few pins found: skip the frame
        print(f"skipped {row['image_name']}: {e}")
        continue
    inputs.append(d)
    targets.append([float(row["pose_2"]), float(row["pose_6"])])  # r mm, theta deg
inputs, targets = np.array(inputs), np.array(targets)
print(f"{len(inputs)} frames -> {inputs.shape} displacements in "
      f"{time.perf_counter() - t0:.1f} s")

# %% Train a PDenNN on 80 % of them; the other 20 % are held out
model = tactrace.train("pdennn", inputs, targets, extractor.reference_pins,
                       epochs=args.epochs, val_fraction=0.2, split_seed=1)
v = model.validation
print(f"held out {v['samples']} frames: position MAE {v['position_mae_mm']:.3f} mm, "
      f"angle MAE {v['angle_mae_deg']:.2f} deg")
pred = model.predict(inputs, reference_pins=extractor.reference_pins)
model_dir = model.save(args.out / "model", force=True)
print(f"model saved to {model_dir} (usable by `tactrace predict --model`)")

# %% A simulated tap and its displacement vector
tip = tactrace.SimTacTip()
frame = tip.render(r_mm=1.0, theta_deg=10.0)
sim_pins = tactrace.PinExtractor(tip.render_rest(), preset="sim")
print("simulated tap:", frame.shape, frame.dtype, "->",
      sim_pins.displacement(frame).shape, "displacements")

# %% Follow the flower in simulation with a model trained on simulated taps
# (a real-frame model sees real pin order: the simulator lists pins otherwise)
sim_set = args.out / "sim_flower"
if not sim_set.exists():
    xs, ys = [], []
    rng = np.random.default_rng(11)
    for _ in range(400):
        r, theta = rng.uniform(-5, 5), rng.uniform(-45, 45)
        depth = rng.uniform(5.25, 7.25)
        xs.append(sim_pins.displacement(tip.render(r, theta, depth, noise=True)))
        ys.append([r, theta])
    tactrace.save_dataset(sim_set, np.array(xs), np.array(ys),
                          {"reference_pins": sim_pins.reference_pins, "source": "simulated"})
x, y, meta = tactrace.load_dataset(sim_set)
sim_model = tactrace.train("pdennn", x, y, meta["reference_pins"], epochs=60)
run = tactrace.follow(sim_model, "flower", out=args.out / "flower_run", force=True, check=False)
print(f"flower: {run['steps']} steps, closed {run['closed']}, mean L2 "
      f"{run['mean_l2_mm']:.2f} mm, coverage {100 * run['coverage']:.0f}%")

# %% Plots, if matplotlib is there
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib not installed: no plots (pip install matplotlib)")
else:
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, k, name in [(axes[0], 0, "r (mm)"), (axes[1], 1, "theta (deg)")]:
        ax.scatter(targets[:, k], pred[:, k], s=3)
        ax.set_xlabel(f"true {name}")
        ax.set_ylabel(f"predicted {name}")
    axes[2].plot(run["x_mm"], run["y_mm"], lw=1)
    axes[2].set_aspect("equal")
    axes[2].set_title("flower, followed")
    fig.tight_layout()
    png = args.out / "python_example.png"
    fig.savefig(png, dpi=100)
    print(f"plots: {png}")
