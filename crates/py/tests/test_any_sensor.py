"""Any TacTip from Python: `inspect_sensor`, `preprocess`, `PinReader` and
`import_dataset` with named targets, checked against the CLI on the same
synthetic frames of a 331-pin TacTip (a centre pin and 10 concentric
rings of 6k pins, raw colour camera images with a bright rim), and the
N-output predictions of a model trained on them."""

import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

import tactrace
from conftest import run_cli

SIZE = 160
CENTRE = 80.0
FRAMES = 40


def write_png(path: Path, image: np.ndarray) -> None:
    """A uint8 (H, W, 3) array as an 8-bit RGB PNG (no imaging library)."""
    h, w, _ = image.shape
    raw = b"".join(b"\x00" + image[y].tobytes() for y in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def ring_pins() -> np.ndarray:
    """331 rest pins (px): the centre, then rings k = 1..10 of 6k pins, 5.5 px apart."""
    pins = [(CENTRE, CENTRE)]
    for k in range(1, 11):
        n = 6 * k
        a = 2 * np.pi * np.arange(n) / n + (k % 2) * np.pi / n
        pins += list(zip(CENTRE + 5.5 * k * np.cos(a), CENTRE + 5.5 * k * np.sin(a)))
    return np.array(pins)


def camera_frame(depth: float, rx: float, ry: float, seed: int) -> np.ndarray:
    """A raw colour frame of a tap: the pins pushed out by `depth` and
    shifted by the tilts, soft pins on a skin lit from the left, a bright
    rim outside the dome, seeded noise."""
    rest = ring_pins()
    d = rest - CENTRE
    moved = rest + 0.008 * depth * d + 0.04 * np.array([ry, rx])
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    light = 50.0 + 25.0 * x / SIZE
    spots = np.zeros_like(x)
    for px, py in moved:
        x0, y0 = int(px) - 3, int(py) - 3
        sl = (slice(y0, y0 + 8), slice(x0, x0 + 8))
        spots[sl] += np.exp(-((x[sl] - px) ** 2 + (y[sl] - py) ** 2) / (2 * 0.9 ** 2))
    r = np.hypot(x - CENTRE, y - CENTRE)
    rim = ((r >= 68) & (r <= 72)).astype(float)
    noise = np.random.default_rng(seed).normal(0.0, 2.0, x.shape)
    grey = np.clip(light + 140.0 * np.minimum(spots, 1.0) + 120.0 * rim + noise, 0, 255)
    return np.stack([grey + 4, grey, grey - 4], axis=-1).clip(0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def ring_set(tmp_path_factory) -> Path:
    """40 labelled raw frames of the synthetic 331-pin sensor, and no
    undeformed frame: frames/image_N.png, labels.csv (depth mm, rx, ry deg)."""
    root = tmp_path_factory.mktemp("ring331")
    (root / "frames").mkdir()
    rng = np.random.default_rng(7)
    rows = ["image,depth,rx,ry"]
    arrays = []
    for n in range(1, FRAMES + 1):
        depth, rx, ry = rng.uniform(0, 1), rng.uniform(-8, 8), rng.uniform(-8, 8)
        arrays.append(camera_frame(depth, rx, ry, n))
        write_png(root / "frames" / f"image_{n}.png", arrays[-1])
        rows.append(f"image_{n}.png,{depth:.4f},{rx:.4f},{ry:.4f}")
    (root / "labels.csv").write_text("\n".join(rows) + "\n")
    np.save(root / "frames.npy", np.stack(arrays))
    return root


@pytest.fixture(scope="module")
def sensor_file(ring_set) -> Path:
    """The sensor file the CLI proposes for the set."""
    out = ring_set / "cli-sensor.toml"
    run_cli("sensor", "inspect", ring_set / "frames", "--out", out)
    return out


TARGETS = ["depth:mm", "rx:deg", "ry:deg"]


def test_inspect_finds_the_331_pins_on_rings_as_the_cli(ring_set, sensor_file):
    out = ring_set / "py-sensor.toml"
    found = tactrace.inspect_sensor(ring_set / "frames", out=out, picture=ring_set / "py.png")
    assert found["sensor"]["pins"] == 331
    assert found["sensor"]["layout"] == "rings"
    assert found["rings"] == [1] + [6 * k for k in range(1, 11)]
    assert found["sensor"]["frame_size"] == [SIZE, SIZE]
    assert found["preprocess"]["mask"]["radius"] < 68, "the rim is masked out"
    assert found["picture"].shape[2] == 3 and found["picture"].dtype == np.uint8
    assert len(found["frames"]) == 20
    assert out.read_text() == sensor_file.read_text(), "the CLI writes the same file"
    with pytest.raises(tactrace.InputError, match="exists"):
        tactrace.inspect_sensor(ring_set / "frames", out=out)


def test_preprocess_equals_the_cli(ring_set, sensor_file):
    frame = ring_set / "frames" / "image_3.png"
    cli = ring_set / "pre-cli.png"
    run_cli("sensor", "preprocess", frame, "--sensor", sensor_file, "--out", cli)
    expected = tactrace.read_frame(cli)
    colour = camera_frame(0.5, 2.0, -3.0, 3)
    write_png(ring_set / "again.png", colour)
    assert np.array_equal(tactrace.preprocess(frame, sensor_file), expected)
    got = tactrace.preprocess(colour, str(sensor_file))
    run_cli("sensor", "preprocess", ring_set / "again.png", "--sensor", sensor_file,
            "--out", ring_set / "again-cli.png")
    assert np.array_equal(got, tactrace.read_frame(ring_set / "again-cli.png"))
    assert got.dtype == np.uint8 and set(np.unique(got)) <= {0, 255}
    # The simple steps against numpy: grey (OpenCV's fixed point), crop,
    # dome mask, a global threshold.
    settings = {"crop": [10, 20, 150, 140],
                "mask": {"centre": [70.0, 60.0], "radius": 50.0},
                "threshold": {"kind": "global", "level": 120}}
    mine = tactrace.preprocess(colour, settings)
    c = colour.astype(np.uint32)
    grey = ((c[..., 0] * 9798 + c[..., 1] * 19235 + c[..., 2] * 3735 + (1 << 14)) >> 15)
    crop = grey[20:140, 10:150]
    yy, xx = np.mgrid[0:crop.shape[0], 0:crop.shape[1]]
    kept = (xx - 70.0) ** 2 + (yy - 60.0) ** 2 <= 50.0 ** 2
    assert np.array_equal(mine, np.where(kept & (crop > 120), 255, 0).astype(np.uint8))
    with pytest.raises(tactrace.InputError, match="120 x 160|160 x 120"):
        tactrace.preprocess(colour[:120], sensor_file)


def test_import_with_named_targets_matches_the_cli(ring_set, sensor_file):
    common = ["--frames", ring_set / "frames", "--targets", ring_set / "labels.csv",
              "--image-column", "image", "--sensor", sensor_file]
    targets = [a for t in TARGETS for a in ("--target", t)]
    run_cli("import", *common, *targets, "--out", ring_set / "cli-data")
    got = tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv",
                                  ring_set / "py-data", target=TARGETS, image_column="image",
                                  sensor=sensor_file)
    assert got["samples"] == FRAMES and got["frames_total"] == FRAMES
    assert got["estimated_rest"]["pins"] is not None
    x_cli, y_cli, meta_cli = tactrace.load_dataset(ring_set / "cli-data")
    x_py, y_py, meta_py = tactrace.load_dataset(ring_set / "py-data")
    assert np.array_equal(x_cli, x_py) and np.array_equal(y_cli, y_py)
    assert meta_py["target_names"] == ["depth", "rx", "ry"]
    assert meta_py["target_units"] == ["mm", "deg", "deg"]
    assert meta_py["reference_pins"] == meta_cli["reference_pins"]
    pins = len(meta_py["reference_pins"])
    assert pins == 331, "the rest layout estimated from the taps"
    # Frame by frame, from the file or a colour array: the rows import wrote.
    reader = tactrace.PinReader(sensor_file, meta_py["reference_pins"])
    names = meta_py["images"]
    for i in (0, 17, FRAMES - 1):
        path = ring_set / "frames" / names[i]
        assert np.array_equal(reader.displacement(path), x_py[i])
        n = int(names[i].split("_")[1].split(".")[0])
        colour = np.load(ring_set / "frames.npy")[n - 1]
        assert np.array_equal(reader.displacement(colour), x_py[i])
        found, counts = reader.read(path)
        assert found.shape == (pins, 2) and sum(counts.values()) == pins
    # Another split with the same reading (`--like`).
    like = tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv",
                                   ring_set / "py-like", like=ring_set / "py-data", limit=10)
    assert like["samples"] == 10
    with pytest.raises(tactrace.InputError, match="like"):
        tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv",
                                ring_set / "bad", like=ring_set / "py-data", target=TARGETS)


def test_n_output_predictions_are_named_as_the_cli_prints_them(ring_set, sensor_file):
    data = ring_set / "named-data"
    tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv", data,
                            target=TARGETS, image_column="image", sensor=sensor_file)
    model = tactrace.train("mlp", data, epochs=5, seed=3)
    assert model.targets == [
        {"name": "depth", "unit": "mm", "circular": False},
        {"name": "rx", "unit": "deg", "circular": False},
        {"name": "ry", "unit": "deg", "circular": False},
    ]
    table = model.predict_targets(data)
    named = model.predict_targets(data, named=True)
    assert list(named) == ["depth", "rx", "ry"] and table.shape == (FRAMES, 3)
    for k, name in enumerate(named):
        assert np.array_equal(named[name], table[:, k])
    x, _, meta = tactrace.load_dataset(data)
    one = model.predict_targets(x[0], reference_pins=meta["reference_pins"], named=True)
    assert one["rx"] == pytest.approx(table[0, 1], abs=0)
    model.save(ring_set / "named-model")
    printed = run_cli("predict", "--model", ring_set / "named-model", "--data", data).stdout
    lines = printed.strip().splitlines()
    assert lines[0].startswith("depth_mm,rx_deg,ry_deg,")
    cli = np.array([[float(v) for v in line.split(",")[:3]] for line in lines[1:]])
    assert np.allclose(cli, table, atol=5e-5, rtol=0)


def test_marked_roles_reach_the_dataset_and_the_model(ring_set, sensor_file):
    data = ring_set / "roles-data"
    marked = ["depth:mm:position", "rx:deg:angle", "ry:deg"]
    tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv", data,
                            target=marked, image_column="image", sensor=sensor_file)
    _, _, meta = tactrace.load_dataset(data)
    assert meta["target_roles"] == ["position", "angle", None]
    model = tactrace.train("mlp", data, epochs=2, seed=3)
    assert [t.get("role") for t in model.targets] == ["position", "angle", None]
    # A role on a target of the wrong unit is refused before anything is written.
    with pytest.raises(tactrace.InputError, match="position"):
        tactrace.import_dataset(ring_set / "frames", ring_set / "labels.csv",
                                ring_set / "roles-bad", target=["rx:deg:position"],
                                image_column="image", sensor=sensor_file)
    assert not (ring_set / "roles-bad").exists()
