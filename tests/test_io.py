"""Atomic writes, JSON reading and schema versions (main_bench/io.py)."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import pytest

from main_bench.errors import InputError
from main_bench.io import (
    atomic_path,
    atomic_write_json,
    atomic_write_text,
    check_schema_version,
    dumps_json,
    folder_lock,
    read_json,
    sha256_bytes,
    sha256_file,
)


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "out.json"
    atomic_write_json(target, {"schema_version": 1, "a": 1})
    before = target.read_bytes()
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half a fi")
        raise RuntimeError("killed mid-write")
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_written_files_follow_the_umask_not_mkstemps_0600(tmp_path):
    code = ("import os, sys; os.umask(0o022); from main_bench.io import atomic_write_text; "
            "atomic_write_text(sys.argv[1], 'x')")
    subprocess.run([sys.executable, "-c", code, str(tmp_path / "f.txt")], check=True)
    assert stat.S_IMODE(os.stat(tmp_path / "f.txt").st_mode) == 0o644


def test_json_is_stable_and_refuses_nan(tmp_path):
    assert dumps_json({"b": 1, "a": [1.5]}) == '{\n  "a": [\n    1.5\n  ],\n  "b": 1\n}\n'
    with pytest.raises(ValueError):
        dumps_json({"x": float("nan")})
    atomic_write_text(tmp_path / "t.txt", "héllo")
    assert sha256_file(tmp_path / "t.txt") == sha256_bytes("héllo".encode())


def test_read_json_names_the_file(tmp_path):
    with pytest.raises(InputError, match="manifest not found") as info:
        read_json(tmp_path / "missing.json", what="manifest")
    assert str(tmp_path / "missing.json") in str(info.value)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="not a valid manifest"):
        read_json(bad, what="manifest")


def test_schema_version_missing_or_newer_is_refused(tmp_path):
    check_schema_version({"schema_version": 1}, 2, tmp_path, "summary")
    with pytest.raises(InputError, match="no integer schema_version"):
        check_schema_version({}, 1, tmp_path, "summary")
    with pytest.raises(InputError, match="upgrade main-bench"):
        check_schema_version({"schema_version": 3}, 2, tmp_path, "summary")


def test_unwritable_output_paths_are_input_errors(tmp_path):
    a_file = tmp_path / "file.txt"
    a_file.write_text("keep")
    with pytest.raises(InputError, match="cannot write here") as info:
        atomic_write_text(a_file / "inside" / "out.json", "x")
    assert str(a_file / "inside" / "out.json") in str(info.value)
    with pytest.raises(InputError, match="is a folder"):
        atomic_write_text(tmp_path, "x")
    assert a_file.read_text() == "keep"


def test_folder_lock_refuses_a_second_holder_and_dies_with_its_holder(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time; from main_bench.io import folder_lock\n"
        f"with folder_lock({str(tmp_path)!r}, lambda: RuntimeError('busy')):\n"
        "    print('held', flush=True); time.sleep(600)")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(InputError, match="in use"), folder_lock(tmp_path, lambda: InputError("in use")):
            pass
    finally:
        holder.kill()
        holder.wait(timeout=60)
    with (folder_lock(tmp_path, lambda: AssertionError("still held after its holder was killed")),
          pytest.raises(InputError, match="in use"),  # one holder at a time within a process too
          folder_lock(tmp_path, lambda: InputError("in use"))):
        pass


def test_folder_lock_goes_on_unlocked_where_the_file_system_has_no_locks(tmp_path, monkeypatch):
    import errno
    import fcntl

    def no_locks(fd, op):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(fcntl, "flock", no_locks)
    ran = []
    with folder_lock(tmp_path, lambda: AssertionError("refused on a file system without locks")):
        ran.append(True)
    assert ran == [True]
