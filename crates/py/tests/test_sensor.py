"""The simulated TacTip and pin extraction: frames equal `tactrace sensor
render` pixel for pixel; displacements are what a model takes."""

import numpy as np
import pytest

import tactrace
from conftest import real_edge_set, run_cli


@pytest.mark.parametrize("shape,r,theta,depth,arc", [
    ("disk", 0.0, 0.0, None, 0.0),
    ("flower", 1.5, -20.0, 5.0, 40.0),
    ("teardrop", -2.0, 35.0, 7.5, 120.0),
])
def test_render_is_the_cli_render(tmp_path, shape, r, theta, depth, arc):
    png = tmp_path / "tap.png"
    args = ["sensor", "render", "--shape", shape, "--r", r, "--theta", theta, "--arc", arc,
            "--out", png]
    if depth is not None:
        args += ["--depth", depth]
    run_cli(*args)
    frame = tactrace.SimTacTip(shape=shape).render(r, theta, depth, arc_mm=arc)
    assert frame.dtype == np.uint8 and frame.shape == (256, 256)
    assert np.array_equal(frame, tactrace.read_frame(png))


def nearest(a, b):
    """For each point of `a`, the distance to the nearest point of `b`."""
    return np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2).min(axis=1)


def test_a_simulated_tap_gives_254_displacements_near_the_true_pins():
    tip = tactrace.SimTacTip()
    extractor = tactrace.PinExtractor(tip.render_rest(), preset="sim")
    # The detected reference pins (detection order) are the simulator's
    # rest pins (its own order), each within half a pixel.
    assert nearest(extractor.reference_pins, tip.rest_pins).max() < 0.5
    frame = tip.render(1.0, 10.0)
    d = extractor.displacement(frame)
    assert d.shape == (254,) and d.dtype == np.float32
    pins = extractor.extract(frame)
    assert np.array_equal(d, np.concatenate([pins[:, 0] - extractor.reference_pins[:, 0],
                                             pins[:, 1] - extractor.reference_pins[:, 1]])
                          .astype(np.float32))
    # The pins found are where the simulator put them (matched by position).
    truth = tip.true_pins(1.0, 10.0)
    assert np.median(nearest(pins, truth)) < 0.3 and np.abs(d).max() > 1.0, "a tap moves pins"
    # Any dtype and a path work as frames.
    assert np.array_equal(extractor.displacement(frame.astype(np.float64)), d)


def test_noise_is_seeded(tmp_path):
    # The fitted default sensor has no pin jitter; configure some.
    rig = tmp_path / "rig.toml"
    rig.write_text("[sensor.nuisance]\npin_jitter_px = 0.2\n")
    a = tactrace.SimTacTip(seed=3, config=rig).render(0.0, 0.0, noise=True)
    b = tactrace.SimTacTip(seed=3, config=rig).render(0.0, 0.0, noise=True)
    c = tactrace.SimTacTip(seed=4, config=rig).render(0.0, 0.0, noise=True)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    plain = tactrace.SimTacTip(seed=3)
    assert np.array_equal(plain.render(0.0, 0.0, noise=True), plain.render(0.0, 0.0))


def test_bad_taps_and_frames_are_refused(tmp_path):
    tip = tactrace.SimTacTip()
    with pytest.raises(tactrace.InputError, match="--depth 9 mm is outside the contact model"):
        tip.render(0.0, 0.0, 9.0)
    with pytest.raises(ValueError, match="--r must be a finite number"):
        tip.true_pins(float("nan"), 0.0)
    with pytest.raises(tactrace.InputError, match="does not exist"):
        tactrace.read_frame(tmp_path / "none.png")
    with pytest.raises(ValueError, match=r"2-D \(H, W\)"):
        tactrace.PinExtractor(np.zeros((4, 4, 3)))
    extractor = tactrace.PinExtractor(tip.render_rest(), preset="sim")
    with pytest.raises(tactrace.InputError, match="pins"):
        extractor.extract(np.zeros((256, 256), np.uint8))
    with pytest.raises(ValueError, match="unknown shape|not found|cannot read"):
        tactrace.SimTacTip(shape="no-such-shape")


def test_real_frames_predict_as_the_cli(real_set, work):
    data = real_edge_set()
    model_dir = work / "real_model"
    run_cli("train", "--train", real_set, "--epochs", 10, "--out", model_dir)
    model = tactrace.load_model(model_dir)
    reference = data / "frames" / "init_0.png"
    extractor = tactrace.PinExtractor(tactrace.read_frame(reference))
    inputs, _, meta = tactrace.load_dataset(real_set)
    # The same pins in the same order (pins.json read back to the last bit
    # or two: serde_json's fast float parser).
    assert np.allclose(extractor.reference_pins, model.reference_pins, rtol=1e-15, atol=0)
    for k, name in enumerate(meta["images"][:3]):
        frame = data / "frames" / name
        d = extractor.displacement(tactrace.read_frame(frame))
        assert d.shape == (254,)
        assert np.array_equal(d, inputs[k]), "the CLI's import extracts the same vector"
        cli = run_cli("predict", "--model", model_dir, "--image", frame, "--reference",
                      reference).stdout.split()
        r, t = model.predict(d, reference_pins=extractor.reference_pins)
        assert cli[1] == f"{r:.4f},{t:.4f}"


def test_a_calibrated_sensor_renders_as_the_cli(work, tmp_path):
    data = real_edge_set()
    sensor = work / "sensor"
    run_cli("calibrate", "--frames", data / "frames", "--targets", data / "targets.csv",
            "--reference", data / "frames" / "init_0.png", "--samples", 30, "--out", sensor)
    png = tmp_path / "cal.png"
    run_cli("sensor", "render", "--sensor", sensor, "--r", -1.5, "--theta", 12, "--out", png)
    tip = tactrace.SimTacTip(sensor)
    assert tip.calibrated
    assert np.array_equal(tip.render(-1.5, 12.0), tactrace.read_frame(png))
