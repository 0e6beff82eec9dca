"""Where the tests look for the shared data: TACTRACE_SHARED_DATA names the
folder of the sets (as for the Rust tests); an absent set is skipped,
saying so, only under TACTRACE_SKIP_REAL_DATA=1, and fails otherwise."""

import pytest

import conftest


def test_the_shared_folder_follows_its_variable(tmp_path, monkeypatch):
    monkeypatch.setenv("TACTRACE_SHARED_DATA", str(tmp_path))
    monkeypatch.delenv("TACTRACE_REAL_DATA", raising=False)
    assert conftest.shared_data_dir() == tmp_path
    monkeypatch.setenv("TACTRACE_SKIP_REAL_DATA", "1")
    with pytest.raises(pytest.skip.Exception, match="SKIPPED.*tactip127-edge2d"):
        conftest.real_edge_set()
    monkeypatch.delenv("TACTRACE_SKIP_REAL_DATA")
    with pytest.raises(pytest.fail.Exception, match="TACTRACE_SHARED_DATA"):
        conftest.real_edge_set()


def test_a_set_under_the_shared_folder_is_found(tmp_path, monkeypatch):
    edge = tmp_path / "tactip127-edge2d"
    (edge / "frames").mkdir(parents=True)
    (edge / "targets.csv").write_text("pose_id\n")
    (edge / "frames" / "init_0.png").write_bytes(b"")
    monkeypatch.setenv("TACTRACE_SHARED_DATA", str(tmp_path))
    monkeypatch.delenv("TACTRACE_REAL_DATA", raising=False)
    assert conftest.real_edge_set() == edge
