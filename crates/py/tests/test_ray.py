"""The Ray executor end to end: a local Ray cluster on 127.0.0.1 (a head
and one worker node, 1 CPU each, started here and stopped after, even on
failure) runs a small search and a small sim-fit with exactly the results
of the local executor; a cluster nobody listens at and an interpreter
that does not exist are refused with the CLI's exit codes."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import real_edge_set, run_cli

PYTHON = sys.executable
RAY = Path(PYTHON).parent / "ray"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_node(args, log: Path) -> subprocess.Popen:
    """`ray start ARGS --block` in its own process group (so that its
    raylet and GCS are stopped with it, and nothing else is)."""
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    with open(log, "w") as out:
        return subprocess.Popen([str(RAY), "start", "--block", "--num-cpus", "1",
                                 "--disable-usage-stats", *args],
                                stdout=out, stderr=subprocess.STDOUT, env=env,
                                start_new_session=True)


def stop_node(proc: subprocess.Popen):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def alive_nodes(address: str) -> int:
    code = ("import ray; ray.init(address=%r, logging_level='ERROR'); "
            "print(sum(1 for n in ray.nodes() if n['Alive']))" % address)
    got = subprocess.run([PYTHON, "-c", code], capture_output=True, text=True, timeout=120)
    return int(got.stdout.strip().splitlines()[-1]) if got.returncode == 0 else 0


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A head and a worker node on 127.0.0.1; the head's address."""
    assert RAY.is_file(), f"ray is not installed in {PYTHON}'s environment (pip install ray==2.60.0)"
    logs = tmp_path_factory.mktemp("ray-logs")
    port = free_port()
    address = f"127.0.0.1:{port}"
    nodes = []
    try:
        nodes.append(start_node(["--head", "--node-ip-address", "127.0.0.1", "--port", str(port),
                                 "--include-dashboard=false"], logs / "head.log"))
        time.sleep(3)
        nodes.append(start_node(["--address", address, "--node-ip-address", "127.0.0.1"],
                                logs / "worker.log"))
        deadline = time.time() + 90
        while alive_nodes(address) < 2:
            if time.time() > deadline or any(n.poll() is not None for n in nodes):
                text = "\n".join(p.read_text() for p in logs.iterdir())
                pytest.fail(f"the local Ray cluster did not come up:\n{text}")
            time.sleep(1)
        yield address
    finally:
        for n in reversed(nodes):
            stop_node(n)


def ray_args(address):
    return ["--executor", "ray", "--ray-address", address, "--python", PYTHON]


def trials(folder: Path):
    """A search's trials without their wall times."""
    rows = [json.loads(line) for line in (folder / "trials.jsonl").read_text().splitlines()]
    for r in rows:
        r.pop("seconds")
    return rows


def test_issue24_search_on_ray_gives_the_local_trials(cluster, work, sim_set):
    space = Path(__file__).resolve().parents[3] / "configs" / "search" / "pdennn.toml"
    args = ["search", "--train", sim_set, "--space", space, "--trials", 4, "--epochs", 3,
            "--startup", 2, "--batch", 2]
    run_cli(*args, "--out", work / "search-local")
    got = run_cli(*args, "--out", work / "search-ray", *ray_args(cluster))
    assert "2 nodes" in got.stderr, got.stderr
    local, ray = trials(work / "search-local"), trials(work / "search-ray")
    assert len(local) == 4 and ray == local
    assert (work / "search-ray" / "best.toml").read_text() == \
        (work / "search-local" / "best.toml").read_text()


def test_issue24_sim_fit_on_ray_gives_the_local_candidates(cluster, work):
    data = real_edge_set()
    args = ["sim-fit", "--frames", data / "frames", "--targets", data / "targets.csv",
            "--reference", data / "frames" / "init_0.png", "--limit", 60, "--generations", 1,
            "--population", 3, "--renders", 1, "--seed", 2]
    run_cli(*args, "--out", work / "fit-local")
    run_cli(*args, "--out", work / "fit-ray", *ray_args(cluster))
    local = (work / "fit-local" / "search.csv").read_text()
    assert len(local.splitlines()) == 1 + 1 + 3
    assert (work / "fit-ray" / "search.csv").read_text() == local
    assert (work / "fit-ray" / "sensor.toml").read_text() == \
        (work / "fit-local" / "sensor.toml").read_text()


def test_issue24_ray_executor_refuses_what_cannot_run(work, sim_set):
    space = Path(__file__).resolve().parents[3] / "configs" / "search" / "pdennn.toml"
    args = ["search", "--train", sim_set, "--space", space, "--trials", 2, "--epochs", 2]
    missing = run_cli(*args, "--out", work / "no-python", "--executor", "ray",
                      "--python", work / "no-such-python", check=False)
    assert missing.returncode == 2, missing.stderr
    assert "cannot start the Python interpreter" in missing.stderr
    assert "--python or TACTRACE_PYTHON" in missing.stderr
    nobody = run_cli(*args, "--out", work / "no-cluster",
                     *ray_args(f"127.0.0.1:{free_port()}"), check=False)
    assert nobody.returncode == 1, nobody.stderr
    assert "cannot be reached" in nobody.stderr, nobody.stderr
    assert not (work / "no-cluster").exists() and not (work / "no-python").exists()
