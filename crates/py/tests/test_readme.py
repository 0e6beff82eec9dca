"""The README's Python snippet runs as written after the main job: a
miniature `tactrace reproduce --out runs/reproduce` (fewer taps, epochs
and steps; the same folders), then the snippet, in a fresh folder."""

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


def readme_python_snippet() -> str:
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1, "one Python snippet in the README's Python section"
    return blocks[0]


def test_issue20_the_readme_snippet_runs_after_the_main_job(tmp_path):
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
