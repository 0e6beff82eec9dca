"""Issue 20 from Python: predict cannot skip the pin-order check, models
record what they were trained on as the CLI's do, `follow` runs in the
CLI's worlds (a calibrated sensor, real frames), and a folder of the wrong
kind is named with what was expected."""

import json

import numpy as np
import pytest

import tactrace
from conftest import real_edge_set, run_cli


def test_predict_needs_the_pin_order(sim_set, sim_model):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    model = tactrace.load_model(sim_model)
    with pytest.raises(tactrace.InputError, match="pin order of the inputs is needed"):
        model.predict(inputs)
    with pytest.raises(tactrace.InputError, match="pin order of the inputs is needed"):
        model.predict(inputs[0])
    with pytest.raises(tactrace.InputError, match="pin order of the inputs is needed"):
        model.validate(inputs, targets)
    # A dataset carries its pins: a folder or load_dataset's tuple.
    pred = model.predict(inputs, reference_pins=meta["reference_pins"])
    assert np.array_equal(model.predict(sim_set), pred)
    assert np.array_equal(model.predict(str(sim_set)), pred)
    assert np.array_equal(model.predict((inputs, targets, meta)), pred)
    # ... and is refused when ordered otherwise, whichever way it comes.
    swapped = dict(meta, reference_pins=np.array(meta["reference_pins"])[
        [1, 0] + list(range(2, 127))].tolist())
    with pytest.raises(tactrace.InputError, match="not ordered like the model's training data"):
        model.predict((inputs, targets, swapped))
    moved = tactrace.save_dataset(sim_set.parent / "swapped", inputs, targets, swapped,
                                  force=True)
    with pytest.raises(tactrace.InputError, match="swapped: not ordered like the model's"):
        model.predict(moved)
    with pytest.raises(tactrace.InputError, match="given with arrays only"):
        model.predict(sim_set, reference_pins=meta["reference_pins"])


def test_validate_takes_a_dataset_and_counts_training_rows(sim_set, sim_model, work):
    model = tactrace.load_model(sim_model)
    cli = json.loads(run_cli("validate", "--model", sim_model, "--data", sim_set,
                             "--json").stdout)
    assert cli["rows_seen_in_training"] == 400
    with pytest.warns(UserWarning, match="400 of the 400 samples are rows the model"):
        assert model.validate(sim_set) == cli
    other = work / "other_taps"
    run_cli("collect", "--shape", "flower", "--samples", 50, "--seed", 12, "--out", other)
    got = model.validate(tactrace.load_dataset(other))
    assert got["rows_seen_in_training"] == 0 and got["samples"] == 50


def test_python_training_records_its_rows_as_the_cli(sim_set, work, tmp_path):
    cli_dir = work / "model_split_5"
    run_cli("train", "--train", sim_set, "--epochs", 3, "--val-fraction", 0.2,
            "--split-seed", 5, "--out", cli_dir)
    cli = json.loads((cli_dir / "training.json").read_text())
    model = tactrace.train("pdennn", tactrace.load_dataset(sim_set), epochs=3,
                           val_fraction=0.2, split_seed=5)
    ours = model.training
    assert ours["dataset"]["path"] is None and cli["dataset"]["path"] == str(sim_set)
    for key in ["sha256", "rows", "source"]:
        assert ours["dataset"][key] == cli["dataset"][key], key
    for key in ["train_rows", "split", "row_hashes", "images"]:
        assert ours[key] == cli[key], key
    assert model.validation["rows_seen_in_training"] == 0
    assert model.validation["samples"] == 80
    # Arrays from Python hash alike; a folder records its path.
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    arrays = tactrace.train("pdennn", inputs, targets, meta["reference_pins"], epochs=1)
    assert arrays.training["dataset"]["sha256"] == cli["dataset"]["sha256"]
    assert arrays.training["dataset"]["source"] == "python"
    folder = tactrace.train("pdennn", sim_set, epochs=1)
    assert folder.training["dataset"]["path"] == str(sim_set)
    # Saved, the CLI scores exactly its held-out rows.
    saved = model.save(tmp_path / "m")
    assert tactrace.load_model(saved).training == ours
    got = json.loads(run_cli("validate", "--model", saved, "--data", sim_set, "--json",
                             "--val-fraction", 0.2, "--split-seed", 5).stdout)
    assert got == model.validation


def test_wrong_folders_are_named_alike(sim_set, sim_model):
    with pytest.raises(tactrace.InputError) as err:
        tactrace.load_dataset(sim_model)
    assert "not a dataset directory: this is a model folder" in str(err.value)
    assert "a dataset folder holds inputs.npy, targets.npy and meta.json" in str(err.value)
    cli = run_cli("validate", "--model", sim_model, "--data", sim_model, check=False)
    assert cli.returncode == 2 and cli.stderr.strip() == f"error: {err.value}"
    with pytest.raises(tactrace.InputError) as err:
        tactrace.load_model(sim_set)
    assert "not a model directory: this is a dataset folder" in str(err.value)
    assert "a model folder holds model.json, weights.safetensors and pins.json" in str(
        err.value)


@pytest.fixture(scope="session")
def calibrated_sensor(work):
    data = real_edge_set()
    out = work / "sensor20"
    run_cli("calibrate", "--frames", data / "frames", "--targets", data / "targets.csv",
            "--reference", data / "frames" / "init_0.png", "--samples", 30, "--out", out)
    return out


@pytest.fixture(scope="session")
def real_model(work, real_set):
    out = work / "real_model20"
    run_cli("train", "--train", real_set, "--epochs", 10, "--out", out)
    return out


def test_follow_in_a_calibrated_sensor_as_the_cli(real_model, calibrated_sensor,
                                                          work, tmp_path):
    cli_dir = work / "sensor_run"
    run_cli("follow", "--model", real_model, "--sensor", calibrated_sensor, "--shape",
            "disk", "--steps", 15, "--out", cli_dir)
    run = tactrace.follow(real_model, "disk", out=tmp_path / "run", steps=15,
                          sensor=calibrated_sensor)
    for name in ["config.toml", "trajectory.csv", "metrics.json"]:
        assert (cli_dir / name).read_bytes() == (run["dir"] / name).read_bytes(), name
    # Without the sensor, a real-trained model meets the simulator's pins.
    with pytest.raises(tactrace.InputError, match="not ordered like the model's"):
        tactrace.follow(real_model, "disk", steps=2)


def test_follow_in_the_real_frame_world_as_the_cli(real_model, real_set, work,
                                                         tmp_path):
    data = real_edge_set()
    cli_dir = work / "replay_run"
    cli = run_cli("follow", "--model", real_model, "--shape", "disk", "--replay", data,
                  "--replay-keep", "N%5==0", "--steps", 10, "--out", cli_dir, check=False)
    assert cli.returncode in (0, 1), cli.stderr
    # The model's 300 training frames include some with N % 5 == 0: said.
    _, _, meta = tactrace.load_dataset(real_set)
    seen = sum(int(name.split("_")[1]) % 5 == 0 for name in meta["images"])
    assert seen > 0
    with pytest.warns(UserWarning, match=f"{seen} of the bank's"):
        run = tactrace.follow(real_model, "disk", out=tmp_path / "run", steps=10, check=False,
                              replay={"dir": data, "keep": "N%5==0"})
    assert run["replay"]["bank_frames_seen_in_training"] == seen
    cli_run = cli_dir if cli_dir.is_dir() else cli_dir.with_name("replay_run.partial")
    for name in ["trajectory.csv", "metrics.json", "answers.csv"]:
        assert (cli_run / name).read_bytes() == (run["dir"] / name).read_bytes(), name
    assert run["replay"]["taps"] == 10
    # The whole collection holds the model's 300 training frames: a warning.
    with pytest.warns(UserWarning, match="are frames the model was trained on"):
        got = tactrace.follow(real_model, "disk", steps=5, check=False, replay=data)
    assert got["replay"]["bank_frames_seen_in_training"] == 300
    with pytest.raises(tactrace.InputError, match="unknown key `kep`"):
        tactrace.follow(real_model, "disk", replay={"dir": data, "kep": "N%5==0"})
    with pytest.raises(tactrace.InputError, match="not a labelled collection"):
        tactrace.follow(real_model, "disk", replay=tmp_path)


def test_a_list_of_datasets_trains_as_their_rows_joined(sim_set, tmp_path):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    halves = [tactrace.save_dataset(tmp_path / name, inputs[rows], targets[rows], meta)
              for name, rows in [("a", slice(0, 30)), ("b", slice(30, None))]]
    whole = tactrace.train("pdennn", sim_set, epochs=2, val_fraction=0.2)
    joined = tactrace.train("pdennn", [str(h) for h in halves], epochs=2, val_fraction=0.2)
    assert joined.validation == whole.validation
    assert np.array_equal(joined.predict(sim_set), whole.predict(sim_set))
    record = joined.training
    assert record["dataset"]["sha256"] == whole.training["dataset"]["sha256"]
    assert [d["rows"] for d in record["datasets"]] == [30, len(inputs) - 30]
    swapped = dict(meta, reference_pins=np.array(meta["reference_pins"])[
        [1, 0] + list(range(2, 127))].tolist())
    other = tactrace.save_dataset(tmp_path / "swapped", inputs, targets, swapped)
    with pytest.raises(tactrace.InputError, match="their reference pins differ"):
        tactrace.train("pdennn", [halves[0], other], epochs=1)
