"""Image datasets and image models from Python (issue 22): `frames.npy` as
`import --frames-size` writes it, read with numpy; `train("conv-mlp", ...)`,
`load_model` of an image model folder, and predictions from frames,
against the CLI on the same data."""

import json

import numpy as np
import pytest

import tactrace
from conftest import real_edge_set, run_cli


@pytest.fixture(scope="module")
def image_set(tmp_path_factory):
    """80 real frames imported by the CLI with 32 px frames."""
    data = real_edge_set()
    out = tmp_path_factory.mktemp("image") / "ds"
    run_cli("import", "--frames", data / "frames", "--targets", data / "targets.csv",
            "--reference", data / "frames" / "init_0.png", "--limit", 80,
            "--frames-size", 32, "--out", out)
    return out


SMALL = {"dense": [16], "conv": [{"channels": 6, "kernel": 3, "stride": 2},
                                 {"channels": 8, "kernel": 3, "stride": 2}]}


def test_frames_npy_is_uint8_n_by_size_and_described_in_meta(image_set):
    frames = np.load(image_set / "frames.npy")
    meta = json.loads((image_set / "meta.json").read_text())
    assert frames.dtype == np.uint8
    assert frames.shape == (meta["samples"], 32, 32) == (80, 32, 32)
    info = meta["image_frames"]
    assert (info["file"], info["height"], info["width"]) == ("frames.npy", 32, 32)
    assert info["source_size"] == [256, 256]
    # The 256 px binarised frame area-averaged by 8 x 8 blocks.
    first = tactrace.read_frame(real_edge_set() / "frames" / meta["images"][0])
    blocks = first.reshape(32, 8, 32, 8).astype(np.float64).mean(axis=(1, 3))
    assert np.abs(frames[0].astype(np.float64) - blocks).max() <= 0.5 + 1e-9


def test_train_load_and_predict_an_image_model(image_set, tmp_path):
    model = tactrace.train("conv-mlp", str(image_set), epochs=3, seed=2, config=SMALL,
                           val_fraction=0.25)
    assert isinstance(model, tactrace.ImageModel)
    assert model.kind == "conv-mlp" and model.input_size == (32, 32)
    assert [t["name"] for t in model.targets] == ["pose_2", "pose_6"]
    assert len(model.history) == 3
    frames = np.load(image_set / "frames.npy")
    out = model.predict(frames[:5])
    assert out.shape == (5, 2) and np.isfinite(out).all()
    # A full-size frame is area-averaged to the input first: same answer.
    meta = json.loads((image_set / "meta.json").read_text())
    big = tactrace.read_frame(real_edge_set() / "frames" / meta["images"][0])
    np.testing.assert_allclose(model.predict(big)[0], out[0], rtol=0, atol=1e-9)
    saved = model.save(tmp_path / "m")
    loaded = tactrace.load_model(saved)
    assert isinstance(loaded, tactrace.ImageModel)
    np.testing.assert_array_equal(loaded.predict(frames[:5]), out)
    # The CLI reads the same folder and gives the same figures.
    with pytest.warns(UserWarning, match="rows the model was trained on"):
        got = loaded.validate(str(image_set))
    cli = json.loads(run_cli("validate", "--model", saved, "--data", image_set,
                             "--json").stdout)
    assert got["per_target"] == cli["per_target"]
    assert got["rows_seen_in_training"] == cli["rows_seen_in_training"] == 60


def test_an_image_model_needs_a_dataset_with_frames(sim_set):
    with pytest.raises(tactrace.InputError, match="frames.npy"):
        tactrace.train("conv-dennn", str(sim_set), epochs=1)
