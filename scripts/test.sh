#!/usr/bin/env bash
# The project's test command: the Rust workspace, then the Python package.
#
# 1. a virtual environment in target/py-venv (reused when present) with
#    maturin, numpy, pytest, ur_rtde and ray from the package registry
#    (ray: crates/py/tests/test_ray.py starts a local two-node Ray cluster
#    and runs search and sim-fit on it);
# 2. `cargo test --workspace --release --tests`, then `--doc`: the unit
#    tests (libraries and binaries), each crate's integration tests (one
#    binary a crate, `tests/it/`) and the doc tests (builds
#    target/release/tactrace, which the Python tests compare with; the
#    RTDE conformance test runs ur_rtde from the venv). The examples are
#    left out of this build: `.ci/run`'s clippy checks them. The Python
#    package's crate (crates/py, a workspace member with no Rust tests) is
#    not built here, but it is in the selection, so every crate it shares
#    is compiled with the features its own build asks for (an explicit
#    `--lib` would build its test binary, which cannot link; `--doc` warns
#    that a cdylib has no doc tests, and it has none);
# 3. `pip install ./crates/py`: maturin through pip builds the package's
#    crate in the same workspace and target folder, reusing every crate
#    step 2 compiled (only pyo3, numpy and the package's crate compile);
# 4. pytest on crates/py/tests.
#
# Each step prints how many seconds it took. Exits non-zero on any
# failure, including a pytest run that collected no test.
# TACTRACE_PYTHON picks the interpreter (default python3).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
# `timed NAME COMMAND...`: runs the command, then says how long it took.
timed() {
    local name=$1 start=$SECONDS
    shift
    "$@"
    echo "$name: $((SECONDS - start)) s"
}

python=${TACTRACE_PYTHON:-python3}
venv=$root/target/py-venv
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
export PATH=$venv/bin:$PATH
# The venv's interpreter, with ur_rtde, checks the fake RTDE controller
# (crates/hw/tests/it/rtde_conformance.rs; required here, not skipped).
pip install --quiet --disable-pip-version-check \
    "maturin==1.16.0" "numpy==2.4.6" "pytest==9.2.0" "ur_rtde==1.6.5" "ray==2.60.0"
export TACTRACE_PYTHON=$venv/bin/python TACTRACE_REQUIRE_UR_RTDE=1

timed "rust tests (build and run)" cargo test --workspace --release --tests
timed "rust doc tests" cargo test --workspace --release --doc

# The build requirements are installed above: no isolated build
# environment to download them into again.
timed "python package built and installed" \
    pip install --quiet --disable-pip-version-check --no-build-isolation \
    --force-reinstall --no-deps ./crates/py

status=0
start=$SECONDS
python -m pytest -q -rs crates/py/tests || status=$?
echo "pytest: $((SECONDS - start)) s"
if [ "$status" -eq 5 ]; then
    echo "pytest collected no test: failing" >&2
    exit 1
fi
exit "$status"
