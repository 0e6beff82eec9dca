"""The README's Python snippets run as written: the first after the main
job (a miniature `tactrace reproduce --out runs/reproduce`: fewer taps,
epochs and steps; the same folders), the second (your own sensor's raw
frames) on a synthetic 331-pin collection in the Bristol layout, each in
a fresh folder."""

import re
import subprocess
import sys

from conftest import ROOT, run_cli

# The main job, small: the folders the snippet reads are the same.
MINIATURE = """train_samples = 400
val_samples = 100
epochs = 60
[follow.follow]
max_steps = 40
"""


def readme_python_snippets() -> list:
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 2, "two Python snippets in the README's Python section"
    return blocks


def readme_python_snippet() -> str:
    return readme_python_snippets()[0]


def test_the_readme_snippet_runs_after_the_main_job(tmp_path):
    snippet = readme_python_snippet()
    read = set(re.findall(r'"(runs/[^"]+)"', snippet))
    assert read == {"runs/reproduce/data/val", "runs/reproduce/models/pdennn"}, read
    (tmp_path / "small.toml").write_text(MINIATURE)
    run_cli("reproduce", "--config", "small.toml", "--out", "runs/reproduce", cwd=tmp_path)
    for path in read:
        assert (tmp_path / path).is_dir(), f"the main job does not write {path}"
    got = subprocess.run([sys.executable, "-c", snippet], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert got.returncode == 0, got.stderr
    lines = got.stdout.strip().splitlines()
    assert "'rows_seen_in_training': 0" in lines[0], lines[0]
    assert lines[-1].startswith("True "), "the flower closed: " + got.stdout


def test_the_readme_sensor_snippet_runs_on_raw_frames(tmp_path):
    from test_any_sensor import camera_frame, write_png
    import numpy as np

    snippet = readme_python_snippets()[1]
    frames = tmp_path / "my-set" / "frames"
    frames.mkdir(parents=True)
    rng = np.random.default_rng(5)
    rows = ["sensor_image,pose_3,pose_4,pose_5"]
    for n in range(1, 121):
        depth, rx, ry = rng.uniform(0, 1), rng.uniform(-8, 8), rng.uniform(-8, 8)
        write_png(frames / f"image_{n}.png", camera_frame(depth, rx, ry, n))
        rows.append(f"image_{n}.png,{depth:.4f},{rx:.4f},{ry:.4f}")
    (tmp_path / "my-set" / "targets.csv").write_text("\n".join(rows) + "\n")
    got = subprocess.run([sys.executable, "-c", snippet], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert got.returncode == 0, got.stderr
    lines = got.stdout.strip().splitlines()
    assert lines[0] == "331 rings", got.stdout
    assert "'name': 'pose_5', 'unit': 'deg'" in lines[1], lines[1]
    assert lines[-1].startswith("{'pose_3': "), lines[-1]
