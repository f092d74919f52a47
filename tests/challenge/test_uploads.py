"""Archive intake on its own: every hostile archive is refused with its reason, leaving nothing behind."""

from __future__ import annotations

import tarfile

import pytest
from hostile import hostile_archives, many_files, zip_bomb

from main_bench.challenge.uploads import Caps, unpack
from main_bench.errors import ChallengeError

CAPS = Caps(upload_bytes=5 * 2**20, files=100, unpacked_bytes=2 * 2**20)


def _snapshot(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.mark.parametrize("name", sorted(hostile_archives()))
def test_hostile_archive_is_refused_and_nothing_is_written(tmp_path, name):
    data, words = hostile_archives()[name]
    box = tmp_path / "box"
    box.mkdir()
    (box / "upload").write_bytes(data)
    before = _snapshot(tmp_path)
    with pytest.raises(ChallengeError, match=words) as err:
        unpack(box / "upload", box / "unpacked", CAPS)
    assert str(err.value).startswith("upload refused: ") and "\n" not in str(err.value)
    assert err.value.status == 400
    assert _snapshot(tmp_path) == before  # the unpacked folder is removed again, nothing outside it
    for escaped in ("/tmp/escaped_abs.py", "/etc/escaped.conf"):
        assert not __import__("os").path.exists(escaped)


def test_a_zip_bomb_stops_at_the_cap_while_streaming(tmp_path):
    (tmp_path / "bomb.zip").write_bytes(zip_bomb(64 * 2**20))
    assert (tmp_path / "bomb.zip").stat().st_size < 2**20  # a small upload...
    with pytest.raises(ChallengeError, match="unpacks to more than 2 MiB") as err:
        unpack(tmp_path / "bomb.zip", tmp_path / "out", CAPS)  # ...that would unpack to 64 MiB
    assert err.value.status == 413 and not (tmp_path / "out").exists()


def test_too_many_files_is_refused(tmp_path):
    (tmp_path / "many.tar.gz").write_bytes(many_files(10_000))
    with pytest.raises(ChallengeError, match="more than 100 files") as err:
        unpack(tmp_path / "many.tar.gz", tmp_path / "out", CAPS)
    assert err.value.status == 413 and not (tmp_path / "out").exists()


def test_a_good_folder_unpacks_with_its_subfolders(tmp_path):
    from main_bench.challenge.client import pack

    src = tmp_path / "src" / "team:policy --x"
    (src / "weights").mkdir(parents=True)
    (src / "policy.py").write_text("class Policy: ...\n")
    (src / "weights" / "w.npy").write_bytes(b"\x93NUMPY")
    (tmp_path / "up.tar.gz").write_bytes(pack(src))
    got = unpack(tmp_path / "up.tar.gz", tmp_path / "out", CAPS)
    assert got.root == tmp_path / "out" and got.files == 2
    with tarfile.open(tmp_path / "nested.tar.gz", "w:gz") as tar:  # the folder itself at the archive's top
        tar.add(src, arcname=src.name)
    nested = unpack(tmp_path / "nested.tar.gz", tmp_path / "out2", CAPS)
    assert nested.root == tmp_path / "out2" / "policy" and (nested.root / "weights" / "w.npy").is_file()
    assert (got.root / "weights" / "w.npy").read_bytes() == b"\x93NUMPY"
    (src / "link").symlink_to("/etc/passwd")
    with pytest.raises(ChallengeError, match="link"):
        pack(src)
