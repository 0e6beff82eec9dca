"""A joined model (`tactrace ensemble`) in Python: loaded as any model, it
predicts the CLI's numbers, and they are its members' mean."""

import numpy as np

import tactrace
from conftest import run_cli
from test_model import cli_predictions


def test_a_joined_model_predicts_the_cli_numbers_and_the_mean(sim_set, work):
    members = []
    for seed in (1, 2):
        config = work / f"joined_member_{seed}.toml"
        config.write_text(f"seed = {seed}\n")
        out = work / f"joined_member_{seed}"
        run_cli("train", "--model", "pdennn", "--train", sim_set, "--epochs", 3,
                "--config", config, "--out", out)
        members.append(out)
    joined = work / "joined"
    run_cli("ensemble", "--member", members[0], "--member", members[1], "--out", joined)
    inputs, _, meta = tactrace.load_dataset(sim_set)
    pins = meta["reference_pins"]
    model = tactrace.load_model(joined)
    assert model.config["ensemble"] == 2
    pred = model.predict(inputs, reference_pins=pins)
    assert pred.shape == (400, 2)
    assert [[f"{r:.4f}", f"{t:.4f}"] for r, t in pred] == cli_predictions(joined, sim_set)
    # r and theta of the edge task are not circular: the plain mean.
    a, b = (tactrace.load_model(m).predict(inputs, reference_pins=pins) for m in members)
    assert not np.array_equal(a, b)
    assert np.allclose(pred, (a + b) / 2, atol=1e-4)
