"""Shared fixtures: the `tactrace` binary the Python results are compared
with, and the data and models it makes (once per session)."""

import os
import signal
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
SKIP_VAR = "TACTRACE_SKIP_REAL_DATA"
SHARED_VAR = "TACTRACE_SHARED_DATA"


def cli_path() -> Path:
    """The release binary (built by `cargo test --workspace --release`)."""
    path = Path(os.environ.get("TACTRACE_BIN", ROOT / "target" / "release" / "tactrace"))
    if not path.is_file():
        pytest.fail(f"the tactrace binary is not at {path}: run `cargo build --release` first "
                    "(or set TACTRACE_BIN)")
    return path


def run_cli(*args, cwd=None, check=True) -> subprocess.CompletedProcess:
    """Run `tactrace ARGS` and return its completed process."""
    got = subprocess.run([str(cli_path()), *map(str, args)], cwd=cwd,
                         capture_output=True, text=True)
    if check and got.returncode != 0:
        raise AssertionError(f"tactrace {' '.join(map(str, args))} exited "
                             f"{got.returncode}: {got.stderr}")
    return got


@pytest.fixture
def ctrl_c():
    """Python's own Ctrl-C handler for the test, whatever the runner was
    started with: a shell's background job (`cmd &`) inherits SIGINT
    ignored, and then `_thread.interrupt_main` delivers nothing."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.fixture(scope="session")
def work(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("cli")


@pytest.fixture(scope="session")
def sim_set(work) -> Path:
    """400 simulated taps on the flower (seed 11), made by the CLI."""
    out = work / "ds"
    run_cli("collect", "--shape", "flower", "--samples", 400, "--seed", 11, "--out", out)
    return out


@pytest.fixture(scope="session")
def sim_model(work, sim_set) -> Path:
    """A PDenNN trained by the CLI on `sim_set` (60 epochs)."""
    out = work / "model"
    run_cli("train", "--train", sim_set, "--epochs", 60, "--out", out)
    return out


def shared_data_dir() -> Path:
    """The folder of the shared sets: TACTRACE_SHARED_DATA when set, else
    ../shared/data beside the repository (as the Rust tests find it)."""
    given = os.environ.get(SHARED_VAR)
    return Path(given) if given else ROOT.parent / "shared" / "data"


def real_edge_set() -> Path:
    """The real TacTip edge set, as the Rust tests find it
    (TACTRACE_REAL_DATA, else tactip127-edge2d in the shared folder): a
    missing set fails the test unless TACTRACE_SKIP_REAL_DATA=1 (then it
    is skipped, saying why)."""
    given = os.environ.get("TACTRACE_REAL_DATA")
    path = Path(given) if given else shared_data_dir() / "tactip127-edge2d"
    if (path / "targets.csv").is_file() and (path / "frames" / "init_0.png").is_file():
        return path
    if os.environ.get(SKIP_VAR) == "1":
        pytest.skip(f"SKIPPED ({SKIP_VAR}=1): real TacTip data not found at {path}")
    pytest.fail(f"real TacTip data not found at {path}: this test needs it (the README says "
                f"where ../shared comes from). Set {SHARED_VAR}=DIR to point at the folder of "
                f"the sets (TACTRACE_REAL_DATA=DIR for the edge set alone), or {SKIP_VAR}=1 "
                f"to skip the tests that need it.")


@pytest.fixture(scope="session")
def real_set(work) -> Path:
    """The first 300 real frames imported by the CLI."""
    data = real_edge_set()
    out = work / "real"
    run_cli("import", "--frames", data / "frames", "--targets", data / "targets.csv",
            "--reference", data / "frames" / "init_0.png", "--limit", 300, "--out", out)
    return out
