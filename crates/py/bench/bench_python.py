"""Speed of the Python package against the CLI (docs/results.md, "Python
package"). Usage, from the repository root after `scripts/test.sh`:

    target/py-venv/bin/python crates/py/bench/bench_python.py \
        --model runs/reproduce/models/pdennn \
        --real-frames ../shared/data/tactip127-edge2d/frames

It measures (wall clock, one thread, best of several repeats):
1. the overhead of one Python call on a 254-value vector: one
   `Model.predict(vector)` less the per-row time of a 10k batch;
2. `predict` on 10 000 samples: `load_dataset` + `load_model` + `predict`
   from Python against `tactrace predict --data` (a process that loads the
   same files and prints every prediction);
3. extraction of 256 x 256 real frames from Python (`PinExtractor.
   displacement` + `Model.predict`) against the same frames in Rust
   (`tactrace bench --real-frames`, frame -> command).
"""

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import tactrace

ROOT = Path(__file__).resolve().parents[3]


def best(f, repeats=5):
    """The fastest of `repeats` timings of f(), seconds."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, type=Path)
    ap.add_argument("--real-frames", required=True, type=Path)
    ap.add_argument("--bin", type=Path, default=ROOT / "target" / "release" / "tactrace")
    ap.add_argument("--frames", type=int, default=2000)
    a = ap.parse_args()
    cli = str(a.bin)
    model = tactrace.load_model(a.model)

    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "ds10k"
        subprocess.run([cli, "collect", "--samples", "10000", "--seed", "3", "--out",
                        str(data)], check=True, capture_output=True)
        inputs, _, meta = tactrace.load_dataset(data)
        pins = np.asarray(meta["reference_pins"])

        # 1. Call overhead on one 254-value vector.
        v = inputs[0].copy()
        n = 20000
        t0 = time.perf_counter()
        for _ in range(n):
            model.predict(v, reference_pins=pins)
        one = (time.perf_counter() - t0) / n
        per_row = best(lambda: model.predict(inputs, reference_pins=pins)) / len(inputs)
        print(f"predict, one 254-value vector: {one * 1e6:.1f} us per call; "
              f"batch per row {per_row * 1e6:.1f} us; overhead {(one - per_row) * 1e6:.1f} us")

        # 2. predict on 10k samples: Python against the CLI.
        def python_predict():
            x, _, m = tactrace.load_dataset(data)
            tactrace.load_model(a.model).predict(x, reference_pins=m["reference_pins"])

        def cli_predict():
            subprocess.run([cli, "predict", "--model", str(a.model), "--data", str(data)],
                           check=True, stdout=subprocess.DEVNULL)

        py_t = best(python_predict)
        predict_only = best(lambda: model.predict(inputs, reference_pins=pins))
        cli_t = best(cli_predict)
        print(f"predict 10k: Python (load + predict) {py_t * 1e3:.1f} ms, predict alone "
              f"{predict_only * 1e3:.1f} ms; CLI `predict --data` {cli_t * 1e3:.1f} ms; "
              f"ratio {py_t / cli_t:.2f}")

    # 3. Extraction of real 256 x 256 frames, the same frames as `bench`.
    paths = sorted(p for p in a.real_frames.glob("*.png") if p.name != "init_0.png")
    frames = [tactrace.read_frame(p) for p in paths[:a.frames]]
    extractor = tactrace.PinExtractor(a.real_frames / "init_0.png")
    # Timing only: the model's own pin order is asserted, as `bench` times
    # any model on the real frames (their predictions are not used).
    own = model.reference_pins

    def python_loop():
        for f in frames:
            model.predict(extractor.displacement(f), reference_pins=own)

    def python_extract():
        for f in frames:
            extractor.displacement(f)

    py_loop = best(python_loop, 3) / len(frames)
    py_ex = best(python_extract, 3) / len(frames)
    rust = []
    for _ in range(3):
        out = subprocess.run([cli, "bench", "--taps", "200", "--model", str(a.model),
                              "--real-frames", str(a.real_frames), "--json"],
                             check=True, capture_output=True, text=True).stdout
        rust.append(json.loads(out)["real_control_latency_us"])
    # `bench --taps N` times the first N real frames; 200 taps keep the
    # simulated part short, so time the same count from Python too.
    few = frames[:200]
    py_few = best(lambda: [model.predict(extractor.displacement(f), reference_pins=own)
                           for f in few], 5) / len(few)
    print(f"real frames, Python: extract {py_ex * 1e6:.0f} us, extract + predict "
          f"{py_loop * 1e6:.0f} us per frame ({len(frames)} frames); first 200 frames "
          f"{py_few * 1e6:.0f} us; Rust `bench --real-frames` (first 200): "
          f"{min(rust):.0f} us; ratio {py_few * 1e6 / min(rust):.2f}")


if __name__ == "__main__":
    main()
