"""The servo loop from Python: `follow` is `tactrace follow` (same metrics,
trajectory and run folder on the same seeds), and a user's own arm and
camera written in Python drive the Rust loop round the flower."""

import _thread
import csv
import json
import threading
import time

import numpy as np
import pytest

import tactrace
from conftest import run_cli


def trajectory_csv(run_dir):
    with open(run_dir / "trajectory.csv") as f:
        return list(csv.DictReader(f))


def test_follow_is_the_cli_follow(sim_model, work, tmp_path):
    cli_dir = work / "cli_run"
    run_cli("follow", "--model", sim_model, "--shape", "flower", "--seed", 4, "--out", cli_dir)
    model = tactrace.load_model(sim_model)
    run = tactrace.follow(model, "flower", out=tmp_path / "run", seed=4)
    metrics = json.loads((cli_dir / "metrics.json").read_text())
    assert {k: run[k] for k in metrics} == metrics
    assert run["closed"] and run["ending"] == "closed" and run["coverage"] > 0.95
    rows = trajectory_csv(cli_dir)
    assert len(rows) == run["steps"] == len(run["x_mm"])
    for name in ["x_mm", "y_mm", "angle_deg", "r_pred_mm", "theta_pred_deg"]:
        assert [r[name] for r in rows] == [f"{v:.4f}" for v in run[name]], name
    for name in ["config.toml", "trajectory.csv", "metrics.json"]:
        assert (cli_dir / name).read_bytes() == (run["dir"] / name).read_bytes(), name
    assert run["l2_curve"].shape == (1000,)
    assert np.isclose(run["l2_curve"].mean(), run["mean_l2_mm"])


def test_follow_without_out_writes_nothing_and_takes_a_folder_or_array(sim_model, tmp_path):
    short = tactrace.follow(str(sim_model), "flower", steps=12)
    assert short["dir"] is None and short["steps"] == 12 and short["ending"] == "steps_done"
    # The same flower as points (mm): a contour given as an array.
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    radius = 60 + 8 * np.cos(5 * t)
    petals = np.column_stack([radius * np.cos(t), radius * np.sin(t)])
    got = tactrace.follow(str(sim_model), petals, steps=12, config={"follow": {"seed": 2}})
    assert got["steps"] == 12 and np.all(got["contact"])


def test_failed_runs_raise_unless_unchecked(sim_model, tmp_path):
    # A contour the sensor cannot stay on (a thin sliver): the run fails.
    sliver = np.array([[0, 0], [120, 0], [120, 0.5], [0, 0.5]], float)
    cfg = {"follow": {"max_steps": 30}}
    with pytest.raises(tactrace.RunFailedError, match="the run failed"):
        tactrace.follow(sim_model, sliver, out=tmp_path / "r", config=cfg)
    assert (tmp_path / "r" / "metrics.json").is_file(), "outputs kept"
    got = tactrace.follow(sim_model, sliver, config=cfg, check=False)
    assert got["succeeded"] is False


def test_bad_follow_input_is_refused(sim_model, tmp_path):
    with pytest.raises(tactrace.InputError):
        tactrace.follow(sim_model, "no-such-shape.csv")
    with pytest.raises(tactrace.InputError, match="unknown field|unknown"):
        tactrace.follow(sim_model, "flower", config={"follow": {"stepz": 3}})
    with pytest.raises(ValueError, match="model must be a Model, an ImageModel or the path"):
        tactrace.follow(3, "flower")
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "x").write_text("x")
    with pytest.raises(tactrace.InputError, match="already exists"):
        tactrace.follow(sim_model, "flower", out=tmp_path / "taken", steps=2)


class PlotterArm:
    """A Python arm: it goes exactly where it is told (a perfect robot)."""

    def __init__(self, start):
        self.where = tuple(start)
        self.moves = 0

    def move_to(self, pose):
        self.where = tuple(pose)
        self.moves += 1

    def pose(self):
        return self.where


class SimCamera:
    """A Python camera: the simulated TacTip seen at the arm's pose."""

    def __init__(self, arm, shape):
        self.arm = arm
        self.tip = tactrace.SimTacTip(shape=shape)

    def capture(self):
        return self.tip.render_at(self.arm.pose())




def test_a_python_arm_and_camera_follow_the_flower(sim_model, tmp_path):
    model = tactrace.load_model(sim_model)
    sim = tactrace.follow(model, "flower", steps=1)
    x, y, angle = sim["x_mm"][0], sim["y_mm"][0], sim["angle_deg"][0]
    arm = PlotterArm((x, y, 2.0, 0.0, 0.0, angle))
    camera = SimCamera(arm, "flower")
    run = tactrace.follow_rig(model, arm, camera, shape="flower", out=tmp_path / "rig")
    assert run["closed"] and run["coverage"] > 0.95 and run["mean_l2_mm"] < 2.0, run["message"]
    assert arm.moves >= 3 * run["steps"] - 1, "tap down, up and each step: through move_to"
    assert (tmp_path / "rig" / "trajectory.csv").is_file()


def test_a_python_arm_that_fails_stops_the_run_with_its_error(sim_model):
    class Fault(RuntimeError):
        pass

    class BrokenArm(PlotterArm):
        def move_to(self, pose):
            if self.moves == 7:
                raise Fault("servo power lost")
            super().move_to(pose)

    model = tactrace.load_model(sim_model)
    sim = tactrace.follow(model, "flower", steps=1)
    arm = BrokenArm((sim["x_mm"][0], sim["y_mm"][0], 2.0, 0.0, 0.0, sim["angle_deg"][0]))
    with pytest.raises(tactrace.RunFailedError, match="servo power lost") as info:
        tactrace.follow_rig(model, arm, SimCamera(arm, "flower"))
    assert isinstance(info.value.__cause__, Fault)


def test_ctrl_c_stops_a_run_and_keeps_its_partial_folder(sim_model, tmp_path, ctrl_c):
    timer = threading.Timer(0.5, _thread.interrupt_main)
    t0 = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        tactrace.follow(sim_model, "disk", out=tmp_path / "run", steps=200000)
    assert time.monotonic() - t0 < 30
    partial = tmp_path / "run.partial"
    assert not (tmp_path / "run").exists() and (partial / "trajectory.csv").is_file()
    assert len(trajectory_csv(partial)) > 0
