"""Datasets: what load_dataset returns is the CLI's files bit for bit, and
what save_dataset writes the CLI reads."""

import json

import numpy as np
import pytest

import tactrace
from conftest import run_cli


def same_json(a, b) -> bool:
    """Equal JSON values, floats to the last bit or two."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(
            same_json(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(same_json, a, b))
    if isinstance(a, float):
        return abs(a - b) <= 4e-16 * max(abs(a), abs(b))
    return a == b


def test_load_dataset_is_the_npy_files(sim_set):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    assert inputs.dtype == np.float32 and targets.dtype == np.float32
    assert inputs.shape == (400, 254) and targets.shape == (400, 2)
    assert np.array_equal(inputs, np.load(sim_set / "inputs.npy"))
    assert np.array_equal(targets, np.load(sim_set / "targets.npy"))
    on_disk = json.loads((sim_set / "meta.json").read_text())
    # The numbers are the ones tactrace's JSON reader gives, which may
    # differ from Python's in the last bit (serde_json's fast float parser).
    assert same_json(meta, on_disk)
    assert len(meta["reference_pins"]) == 127


def test_saved_dataset_is_read_by_the_cli(sim_set, sim_model, tmp_path):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    # float64 in: stored as float32, the same numbers.
    out = tactrace.save_dataset(tmp_path / "copy", inputs.astype(np.float64), targets, meta)
    assert np.array_equal(np.load(out / "inputs.npy"), inputs)
    ours = json.loads(run_cli("validate", "--model", sim_model, "--data", out, "--json").stdout)
    theirs = json.loads(run_cli("validate", "--model", sim_model, "--data", sim_set,
                                "--json").stdout)
    assert ours == theirs


def test_save_dataset_refuses_an_existing_folder_unless_forced(sim_set, tmp_path):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    tactrace.save_dataset(tmp_path / "d", inputs[:10], targets[:10], meta)
    with pytest.raises(tactrace.InputError, match="already exists.*--force"):
        tactrace.save_dataset(tmp_path / "d", inputs[:5], targets[:5], meta)
    tactrace.save_dataset(tmp_path / "d", inputs[:5], targets[:5], meta, force=True)
    assert tactrace.load_dataset(tmp_path / "d")[0].shape == (5, 254)


def test_bad_datasets_are_input_errors_naming_the_problem(sim_set, tmp_path):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    with pytest.raises(tactrace.InputError, match="not a dataset directory"):
        tactrace.load_dataset(tmp_path / "missing")
    with pytest.raises(ValueError, match="inputs has 10 rows but targets has 9"):
        tactrace.save_dataset(tmp_path / "a", inputs[:10], targets[:9], meta)
    with pytest.raises(ValueError, match="reference pins"):
        tactrace.save_dataset(tmp_path / "b", inputs[:10, :100], targets[:10], meta)
    with pytest.raises(ValueError, match="reference_pins"):
        tactrace.save_dataset(tmp_path / "c", inputs[:10], targets[:10], {})
    with pytest.raises(ValueError, match="targets has 254 columns, meta names 2 targets"):
        tactrace.save_dataset(tmp_path / "e", inputs[:10], inputs[:10], meta)
    assert not any(tmp_path.iterdir()), "nothing written"
