"""The Ray executor end to end: a local Ray cluster on 127.0.0.1 (a head
and one worker node, 1 CPU each, started lean as scripts/ray_speedup.sh
starts them, here and stopped after, even on failure) runs a small search
and a small sim-fit with exactly the results of the local executor, on
workers that build each evaluation once; a cluster nobody listens at and
an interpreter that does not exist are refused with the CLI's exit codes.
The driver's chunking and the timings' summary are checked without a
cluster."""

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
from tactrace import ray_timings

PYTHON = sys.executable
RAY = Path(PYTHON).parent / "ray"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


#: What lean nodes are started with (docs/search.md, "Starting the nodes
#: lean"; the same as scripts/ray_speedup.sh): Ray's settings...
LEAN_ENV = {"RAY_enable_metrics_collection": "0", "RAY_task_events_report_interval_ms": "0",
            "RAY_event_stats": "0", "RAY_memory_monitor_refresh_ms": "0",
            "RAY_worker_niceness": "0"}
#: ... and `ray start` options (the head also gets --no-monitor).
LEAN_ARGS = ["--include-log-monitor=false"]


def start_node(args, log: Path) -> subprocess.Popen:
    """`ray start ARGS --block`, lean, in its own process group and
    session (so that its raylet and GCS are stopped with it, and nothing
    else is)."""
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", **LEAN_ENV)
    with open(log, "w") as out:
        return subprocess.Popen([str(RAY), "start", "--block", "--num-cpus", "1",
                                 "--disable-usage-stats", *LEAN_ARGS, *args],
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


NODES = []


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A head and a worker node on 127.0.0.1; the head's address (their
    `ray start` processes in NODES while they run)."""
    assert RAY.is_file(), f"ray is not installed in {PYTHON}'s environment (pip install ray==2.60.0)"
    logs = tmp_path_factory.mktemp("ray-logs")
    port = free_port()
    address = f"127.0.0.1:{port}"
    nodes = []
    try:
        nodes.append(start_node(["--head", "--node-ip-address", "127.0.0.1", "--port", str(port),
                                 "--include-dashboard=false", "--no-monitor"],
                                logs / "head.log"))
        time.sleep(3)
        nodes.append(start_node(["--address", address, "--node-ip-address", "127.0.0.1"],
                                logs / "worker.log"))
        deadline = time.time() + 90
        while alive_nodes(address) < 2:
            if time.time() > deadline or any(n.poll() is not None for n in nodes):
                text = "\n".join(p.read_text() for p in logs.iterdir())
                pytest.fail(f"the local Ray cluster did not come up:\n{text}")
            time.sleep(1)
        NODES[:] = nodes
        yield address
    finally:
        NODES.clear()
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


def test_search_on_ray_gives_the_local_trials(cluster, work, sim_set):
    space = Path(__file__).resolve().parents[3] / "configs" / "search" / "pdennn.toml"
    args = ["search", "--train", sim_set, "--space", space, "--trials", 4, "--epochs", 3,
            "--startup", 2, "--batch", 2]
    run_cli(*args, "--out", work / "search-local")
    got = run_cli(*args, "--out", work / "search-ray", *ray_args(cluster))
    assert "2 nodes" in got.stderr and "2 workers" in got.stderr, got.stderr
    local, ray = trials(work / "search-local"), trials(work / "search-ray")
    assert len(local) == 4 and ray == local
    assert (work / "search-ray" / "best.toml").read_text() == \
        (work / "search-local" / "best.toml").read_text()


def test_sim_fit_on_ray_gives_the_local_candidates(cluster, work):
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


def test_ray_executor_refuses_what_cannot_run(work, sim_set):
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


def node_processes():
    """{pid: command line} of the processes in the nodes' sessions."""
    sessions = {n.pid for n in NODES}
    found = {}
    for entry in Path("/proc").iterdir():
        try:
            stat = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            if int(stat[3]) in sessions:
                found[int(entry.name)] = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except (OSError, ValueError, IndexError):
            continue
    return found


def test_lean_nodes_run_without_monitors_or_metrics(cluster):
    procs = node_processes()
    text = b"\n".join(procs.values()).decode(errors="replace")
    raylets = [p for p, c in procs.items() if c.split(b" ")[0].endswith(b"/raylet")]
    assert len(raylets) == 2, text
    assert "gcs_server" in text, text
    for absent in ["log_monitor", "autoscaler/_private/monitor"]:
        assert absent not in text, f"{absent} runs on a lean node:\n{text}"
    # Without the dashboard the head still runs its process, with no
    # front end and no module but usage stats (which are off).
    for line in text.splitlines():
        if "dashboard/dashboard.py" in line:
            assert "--disable-frontend" in line and "--modules-to-load=UsageStatsHead" in line
    environ = Path(f"/proc/{raylets[0]}/environ").read_bytes().split(b"\0")
    for key, value in LEAN_ENV.items():
        assert f"{key}={value}".encode() in environ, key


def test_workers_build_once_and_time_their_calls(cluster, work, sim_set, monkeypatch):
    space = Path(__file__).resolve().parents[3] / "configs" / "search" / "pdennn.toml"
    args = ["search", "--train", sim_set, "--space", space, "--trials", 6, "--epochs", 2,
            "--startup", 2, "--batch", 2, "--seed", 9]
    run_cli(*args, "--out", work / "timed-local")
    timings = work / "timings.jsonl"
    monkeypatch.setenv("TACTRACE_RAY_TIMINGS", str(timings))
    run_cli(*args, "--out", work / "timed-ray", *ray_args(cluster))
    assert trials(work / "timed-ray") == trials(work / "timed-local")
    calls, driver_cpu = ray_timings.read(timings)
    assert driver_cpu is not None and driver_cpu > 0
    # 3 batches of 2 on 2 workers: one configuration a call, and each
    # worker built the search's evaluation once (its first call) and kept it.
    assert sorted(c["batch"] for c in calls) == [1, 1, 2, 2, 3, 3]
    assert all(c["configs"] == 1 for c in calls)
    workers = {c["worker"] for c in calls}
    assert 1 <= len(workers) <= 2
    for w in workers:
        mine = sorted((c for c in calls if c["worker"] == w), key=lambda c: c["start"])
        assert [c["built"] for c in mine] == [True] + [False] * (len(mine) - 1), mine
    for c in calls:
        assert c["sent"] <= c["start"] <= c["ready"] <= c["end"] <= c["got"], c
        assert c["eval_cpu"] > 0
    s = ray_timings.summarise(calls, driver_cpu)
    assert s["evaluations"] == 6 and s["built"] == len(workers)
    assert s["round_trip"] >= s["evaluation"] > 0


def test_a_large_batch_goes_in_chunks_with_the_local_results(cluster, work, sim_set,
                                                                    monkeypatch):
    space = Path(__file__).resolve().parents[3] / "configs" / "search" / "pdennn.toml"
    args = ["search", "--train", sim_set, "--space", space, "--trials", 16, "--epochs", 1,
            "--startup", 16, "--batch", 16, "--seed", 5]
    run_cli(*args, "--out", work / "chunked-local")
    timings = work / "chunked.jsonl"
    monkeypatch.setenv("TACTRACE_RAY_TIMINGS", str(timings))
    run_cli(*args, "--out", work / "chunked-ray", *ray_args(cluster))
    assert trials(work / "chunked-ray") == trials(work / "chunked-local")
    calls, _ = ray_timings.read(timings)
    # 16 configurations on 2 workers: 8 calls of 2.
    assert sorted(c["configs"] for c in calls) == [2] * 8


def test_chunks_cover_a_batch_in_order():
    from tactrace.ray_executor import CHUNKS_PER_WORKER, chunks

    # A batch of a few per worker goes one configuration at a time.
    assert chunks(8, 2) == [[i] for i in range(8)]
    assert chunks(1, 4) == [[0]]
    assert chunks(0, 2) == []
    # A batch of many short evaluations goes a few at a time, every index
    # once and in order, at least CHUNKS_PER_WORKER chunks a worker.
    got = chunks(1001, 3)
    assert [i for c in got for i in c] == list(range(1001))
    assert len(got) >= 3 * CHUNKS_PER_WORKER and max(map(len, got)) == 1001 // 12


def test_timings_summary_adds_up(tmp_path):
    rows = [
        # worker a: two calls of one batch, built on the first
        {"batch": 1, "worker": "h:1", "configs": 1, "built": True, "sent": 10.0,
         "start": 10.5, "ready": 11.0, "end": 13.0, "got": 13.25,
         "prepare_cpu": 0.4, "eval_cpu": 1.9},
        {"batch": 1, "worker": "h:1", "configs": 2, "built": False, "sent": 13.3,
         "start": 13.5, "ready": 13.5, "end": 17.5, "got": 17.75,
         "prepare_cpu": 0.0, "eval_cpu": 3.8},
        # worker b: one call
        {"batch": 1, "worker": "h:2", "configs": 1, "built": True, "sent": 10.0,
         "start": 10.25, "ready": 10.75, "end": 12.75, "got": 13.0,
         "prepare_cpu": 0.5, "eval_cpu": 2.0},
    ]
    path = tmp_path / "t.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows) + '{"driver_cpu": 0.75}\n')
    s = ray_timings.summarise(*ray_timings.read(path))
    assert (s["calls"], s["evaluations"], s["workers"], s["built"]) == (3, 4, 2, 2)
    assert s["dispatch"] == pytest.approx(0.5 + 0.2 + 0.25)
    assert s["startup"] == pytest.approx(0.5 + 0.0 + 0.5)
    assert s["evaluation"] == pytest.approx(2.0 + 4.0 + 2.0)
    assert s["evaluation_cpu"] == pytest.approx(7.7)
    assert s["return"] == pytest.approx(0.25 * 3)
    assert s["round_trip"] == pytest.approx(3.25 + 4.45 + 3.0)
    assert s["overhead"] == pytest.approx(10.7 - 8.0)
    assert s["idle"] == pytest.approx(13.5 - 13.0)
    assert s["driver_cpu"] == 0.75
    text = "\n".join(ray_timings.report(s))
    assert "4 evaluations in 3 calls on 2 workers (2 builds)" in text
    assert "overhead per evaluation (round trip less evaluation): 0.6750 s, 33.75 %" in text
