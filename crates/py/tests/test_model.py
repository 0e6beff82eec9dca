"""Pose models: predictions, validation and training equal the CLI's bit
for bit; bad input is refused with the CLI's messages."""

import _thread
import json
import threading
import time

import numpy as np
import pytest

import tactrace
from conftest import run_cli


def cli_predictions(model, data):
    lines = run_cli("predict", "--model", model, "--data", data).stdout.split()
    assert lines[0] == "r_mm,theta_deg,true_r_mm,true_theta_deg"
    return [row.split(",")[:2] for row in lines[1:]]


def test_predict_gives_the_cli_numbers(sim_set, sim_model):
    inputs, _, meta = tactrace.load_dataset(sim_set)
    model = tactrace.load_model(sim_model)
    pred = model.predict(inputs, reference_pins=meta["reference_pins"])
    assert pred.shape == (400, 2) and pred.dtype == np.float64
    ours = [[f"{r:.4f}", f"{t:.4f}"] for r, t in pred]
    assert ours == cli_predictions(sim_model, sim_set)
    # One row gives one pose; other dtypes are used as float32.
    pins = meta["reference_pins"]
    assert np.array_equal(model.predict(inputs[7], reference_pins=pins), pred[7])
    assert np.array_equal(model.predict(inputs.astype(np.float64), reference_pins=pins), pred)
    assert np.array_equal(model.predict(inputs.tolist(), reference_pins=pins), pred)


def test_validate_is_the_cli_validate(sim_set, sim_model):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    model = tactrace.load_model(sim_model)
    cli = json.loads(run_cli("validate", "--model", sim_model, "--data", sim_set,
                             "--json").stdout)
    with pytest.warns(UserWarning, match="400 of the 400 samples are rows the model"):
        assert model.validate(inputs, targets, reference_pins=meta["reference_pins"]) == cli


def test_train_is_the_cli_train(sim_set, work, tmp_path):
    out = work / "model_holdout"
    run_cli("train", "--model", "pcadennn", "--train", sim_set, "--epochs", 8,
            "--val-fraction", 0.25, "--split-seed", 3, "--out", out)
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    model = tactrace.train("pcadennn", inputs, targets, meta["reference_pins"], epochs=8,
                           val_fraction=0.25, split_seed=3)
    assert model.kind == "pcadennn" and model.config["epochs"] == 8
    assert model.validation["samples"] == 100
    assert len(model.history) == 8
    saved = model.save(tmp_path / "m")
    for name in ["weights.safetensors", "model.json", "pins.json", "history.csv"]:
        assert (saved / name).read_bytes() == (out / name).read_bytes(), name
    pins = meta["reference_pins"]
    assert np.array_equal(tactrace.load_model(saved).predict(inputs, reference_pins=pins),
                          model.predict(inputs, reference_pins=pins))


def test_config_and_seed_reach_the_model(sim_set):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    pins = meta["reference_pins"]
    a = tactrace.train("pdennn", inputs, targets, pins, epochs=2, seed=5,
                       config={"position": {"hidden": [8]}})
    assert a.config["seed"] == 5 and a.config["position"]["hidden"] == [8]
    b = tactrace.train("pdennn", inputs, targets, pins, epochs=2, seed=6,
                       config={"position": {"hidden": [8]}})
    assert not np.array_equal(a.predict(inputs, reference_pins=pins),
                              b.predict(inputs, reference_pins=pins))


def test_bad_model_input_is_refused(sim_set, sim_model):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    model = tactrace.load_model(sim_model)
    pins = meta["reference_pins"]
    with pytest.raises(tactrace.InputError, match="inputs has 250 columns but there are 127"):
        model.predict(inputs[:, :250], reference_pins=pins)
    with pytest.raises(ValueError, match="inputs must be a N x M array"):
        model.predict(inputs.reshape(400, 2, 127), reference_pins=pins)
    with pytest.raises(ValueError, match="not convertible"):
        model.predict([["a", "b"]], reference_pins=pins)
    swapped = np.array(meta["reference_pins"])[[1, 0] + list(range(2, 127))]
    with pytest.raises(tactrace.InputError, match="not ordered like the model's training data"):
        model.predict(inputs, reference_pins=swapped)
    with pytest.raises(ValueError, match='unknown model kind `cnn`'):
        tactrace.train("cnn", inputs, targets, meta["reference_pins"])
    with pytest.raises(ValueError, match="validation fraction 1.5"):
        tactrace.train("pdennn", inputs, targets, meta["reference_pins"], val_fraction=1.5)
    with pytest.raises(tactrace.InputError, match="not a model directory"):
        tactrace.load_model(sim_set)
    bad = inputs.copy()
    bad[3, 5] = np.nan
    with pytest.raises(tactrace.TactraceError, match="non-finite|NaN|finite"):
        model.predict(bad, reference_pins=pins)


def test_ctrl_c_stops_training(sim_set, ctrl_c):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    timer = threading.Timer(0.5, _thread.interrupt_main)
    t0 = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        tactrace.train("pdennn", inputs, targets, meta["reference_pins"], epochs=100000)
    assert time.monotonic() - t0 < 30


def test_the_gil_is_released_while_training(sim_set):
    inputs, targets, meta = tactrace.load_dataset(sim_set)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.01)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        tactrace.train("pdennn", inputs, targets, meta["reference_pins"], epochs=100)
    finally:
        done.set()
        counter.join()
    gaps = np.diff(ticks)
    assert len(ticks) > 5 and gaps.max() < 0.5, f"Python thread starved: {gaps.max():.2f} s"


def test_errors_carry_the_cli_messages(sim_set, tmp_path):
    got = run_cli("validate", "--model", sim_set, "--data", sim_set, check=False)
    assert got.returncode == 2, "bad input"
    with pytest.raises(tactrace.InputError) as err:
        tactrace.load_model(sim_set)
    assert got.stderr.strip() == f"error: {err.value}"
    got = run_cli("sensor", "render", "--depth", 11, "--out", tmp_path / "x.png", check=False)
    assert got.returncode == 2
    with pytest.raises(tactrace.InputError) as err:
        tactrace.SimTacTip().render(0.0, 0.0, 11.0)
    assert got.stderr.strip() == f"error: {err.value}"


def test_python_messages_have_no_rust_debug_values():
    """Shapes read as numpy prints them; names are quoted once, not Rust-escaped."""
    import numpy as np

    with pytest.raises(tactrace.InputError) as err:
        tactrace.PinExtractor(np.zeros((2, 3, 4), dtype=np.uint8))
    assert "(2, 3, 4)" in str(err.value), str(err.value)
    assert "[2, 3, 4]" not in str(err.value)
    with pytest.raises(ValueError) as err:
        tactrace.train("cnn", np.zeros((40, 4), dtype=np.float32), np.zeros((40, 2)), [])
    assert '"cnn"' not in str(err.value) and "`cnn`" in str(err.value)
