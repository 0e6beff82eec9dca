"""The servo loop from Python with an image model (issue 22): `follow`
takes an `ImageModel` (or its folder) and its perception reads the taps'
pixels, as `tactrace follow --model IMAGE_MODEL` does: the same
trajectory as the CLI on the same seed."""

import json

import numpy as np
import pytest

import tactrace
from conftest import run_cli

SMALL = {"dense": [16], "conv": [{"channels": 4, "kernel": 3, "stride": 2},
                                 {"channels": 8, "kernel": 3, "stride": 2}]}


@pytest.fixture(scope="module")
def image_model(tmp_path_factory):
    """A tiny conv-mlp trained from Python on 120 simulated taps with 32 px
    frames (`collect --frames-size`), saved as a model folder."""
    work = tmp_path_factory.mktemp("image_follow")
    data = work / "ds"
    run_cli("collect", "--shape", "disk", "--samples", 120, "--seed", 5,
            "--frames-size", 32, "--out", data)
    model = tactrace.train("conv-mlp", str(data), epochs=2, seed=1, config=SMALL)
    assert isinstance(model, tactrace.ImageModel)
    return model, model.save(work / "model")


def test_python_follows_with_an_image_model_as_the_cli_does(image_model, tmp_path):
    model, folder = image_model
    run = tactrace.follow(model, "disk", out=tmp_path / "py", steps=8, seed=3)
    assert run["steps"] == 8 and run["ending"] == "steps_done"
    assert np.all(run["contact"]) and np.isfinite(run["r_pred_mm"]).all()
    cli = tmp_path / "cli"
    run_cli("follow", "--model", folder, "--shape", "disk", "--steps", 8, "--seed", 3,
            "--out", cli)
    metrics = json.loads((cli / "metrics.json").read_text())
    assert {k: run[k] for k in metrics} == metrics
    for name in ["trajectory.csv", "metrics.json"]:
        assert (cli / name).read_bytes() == (run["dir"] / name).read_bytes(), name
    # The model's folder is read as an image model too: the same run.
    again = tactrace.follow(str(folder), "disk", steps=8, seed=3)
    np.testing.assert_array_equal(again["r_pred_mm"], run["r_pred_mm"])
    np.testing.assert_array_equal(again["theta_pred_deg"], run["theta_pred_deg"])


def test_the_perception_reads_pixels_not_pins(image_model, sim_model):
    model, _ = image_model
    pixels = tactrace.follow(model, "disk", steps=8, seed=3)
    pins = tactrace.follow(sim_model, "disk", steps=8, seed=3)
    # The first tap is at the same pose in both runs: its percept differs
    # only by the model that read it.
    assert pixels["x_mm"][0] == pins["x_mm"][0] and pixels["y_mm"][0] == pins["y_mm"][0]
    assert pixels["r_pred_mm"][0] != pins["r_pred_mm"][0]


def test_follow_refuses_what_is_not_a_model():
    with pytest.raises(tactrace.InputError, match="an ImageModel"):
        tactrace.follow(3.5, "disk", steps=2)
