"""The residual image model trained from Python (`input =
"pin_model_and_pixels"` with a `[base]` table), as `tactrace train` trains
it: the pin model fitted on every training row and stored inside the
model, the rows' base predictions out of fold (recorded in training.json),
the same refusals; and `views=` of `predict` / `validate`, the CLI's
`--views on|off`."""

import json

import numpy as np
import pytest

import tactrace
from conftest import run_cli

CONV = {"dense": [8], "learning_rate": 0.003, "batch_size": 8,
        "conv": [{"channels": 4, "kernel": 3, "stride": 2}]}
BASE = {"model": "disdennn", "folds": 3, "settings": {"epochs": 20}}
RESIDUAL = {**CONV, "input": "pin_model_and_pixels", "base": BASE}


def toml_of(config):
    """`config` (CONV's keys with an optional base table) as TOML."""
    lines = []
    for key in ("input", "dense", "learning_rate", "batch_size"):
        if key in config:
            lines.append(f"{key} = {json.dumps(config[key])}")
    for layer in config["conv"]:
        lines.append("[[conv]]")
        lines += [f"{k} = {v}" for k, v in layer.items()]
    if "base" in config:
        base = config["base"]
        lines += ["[base]", f'model = "{base["model"]}"', f'folds = {base["folds"]}',
                  "[base.settings]", f'epochs = {base["settings"]["epochs"]}']
    return "\n".join(lines) + "\n"


def scored_on_training_rows(model, data, **kwargs):
    """`model.validate(data)` of rows it was trained on (which it warns of)."""
    with pytest.warns(UserWarning, match="rows the model was trained on"):
        return model.validate(str(data), **kwargs)


@pytest.fixture(scope="module")
def frames_set(tmp_path_factory):
    """60 simulated taps on the disk (seed 7) with their 16 px frames."""
    out = tmp_path_factory.mktemp("residual") / "ds"
    run_cli("collect", "--shape", "disk", "--samples", 60, "--seed", 7,
            "--frames-size", 16, "--out", out)
    return out


def test_a_residual_model_trained_from_python_is_the_clis(frames_set, tmp_path):
    model = tactrace.train("conv-mlp", str(frames_set), epochs=2, seed=5, config=RESIDUAL)
    base = model.training["base"]
    assert base["folds"] == 3 and base["model"] == "disdennn"
    assert len(base["fold_of_row"]) == 60
    saved = model.save(tmp_path / "py")
    (tmp_path / "residual.toml").write_text(toml_of(RESIDUAL))
    run_cli("train", "--model", "conv-mlp", "--train", frames_set, "--epochs", 2,
            "--seed", 5, "--config", tmp_path / "residual.toml", "--out", tmp_path / "cli")
    cli = tactrace.load_model(tmp_path / "cli")
    got = tactrace.load_model(saved)
    assert (tmp_path / "py" / "base" / "pins.json").is_file()
    for m in (got, cli):
        assert m.training["base"]["fold_of_row"] == base["fold_of_row"]
    py_fig = json.loads(run_cli("validate", "--model", tmp_path / "py", "--data", frames_set,
                                "--json").stdout)
    cli_fig = json.loads(run_cli("validate", "--model", tmp_path / "cli", "--data",
                                 frames_set, "--json").stdout)
    assert py_fig["per_target"] == cli_fig["per_target"]


def test_a_fresh_residual_model_predicts_its_pin_models_figures(frames_set, tmp_path):
    config = {**RESIDUAL, "learning_rate": 1e-30}
    model = tactrace.train("conv-mlp", str(frames_set), epochs=1, seed=5, config=config)
    model.save(tmp_path / "fresh")
    image = scored_on_training_rows(model, frames_set)
    pins = json.loads(run_cli("validate", "--model", tmp_path / "fresh" / "base", "--data",
                              frames_set, "--json").stdout)
    for target, score in pins["per_target"].items():
        assert abs(image["per_target"][target]["mae"] - score["mae"]) < 1e-3 * score["mae"]


def test_a_base_table_without_the_residual_input_is_refused(frames_set):
    with pytest.raises(tactrace.InputError, match="base"):
        tactrace.train("conv-mlp", str(frames_set), epochs=1, config={**CONV, "base": BASE})


def test_views_switch_a_turned_copies_model_and_refuse_one_without(frames_set):
    turned = {**CONV, "rotations": {"order": 4, "angle_sign": 1}}
    model = tactrace.train("conv-mlp", str(frames_set), epochs=1, seed=2, config=turned)
    frames = np.load(frames_set / "frames.npy")[:10]
    on, off = model.predict(frames, views=True), model.predict(frames, views=False)
    np.testing.assert_array_equal(model.predict(frames), off)
    assert np.abs(on - off).max() > 1e-6
    assert scored_on_training_rows(model, frames_set, views=True)["turned_views"] is True
    assert scored_on_training_rows(model, frames_set)["turned_views"] is False
    plain = tactrace.train("conv-mlp", str(frames_set), epochs=1, seed=2, config=CONV)
    with pytest.raises(tactrace.InputError, match="not fitted with rotations"):
        plain.predict(frames, views=True)
    assert "turned_views" not in scored_on_training_rows(plain, frames_set)


def test_a_pin_model_without_rotations_refuses_views(sim_set, sim_model):
    model = tactrace.load_model(sim_model)
    with pytest.raises(tactrace.InputError, match="not fitted with rotations"):
        model.predict(str(sim_set), views=False)
    with pytest.raises(tactrace.InputError, match="not fitted with rotations"):
        model.validate(str(sim_set), views=True)
    assert "turned_views" not in scored_on_training_rows(model, sim_set)
