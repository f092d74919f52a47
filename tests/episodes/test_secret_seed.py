"""`episodes generate --secret-seed-file`: a hidden split whose manifest commits to the seed without holding it."""

from __future__ import annotations

import hashlib
import json

import pytest

from main_bench.episodes.dataset import read_manifest
from main_bench.episodes.generation.secret_seed import make_secret_seed, read_secret_seed
from main_bench.errors import InputError

SMALL = ("--only-splits", "val", "--agents", "2", "--task", "shared")


def _all_bytes(folder) -> bytes:
    return b"".join(p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file())


def test_same_secret_same_manifest_and_the_seed_is_nowhere_in_the_folder(gen, tmp_path):
    secret = make_secret_seed(tmp_path / "secrets" / "test.seed")
    text = (tmp_path / "secrets" / "test.seed").read_text().strip()
    a = gen(tmp_path / "a", *SMALL, "--secret-seed-file", tmp_path / "secrets" / "test.seed", per_scene=6)
    b = gen(tmp_path / "b", *SMALL, "--secret-seed-file", tmp_path / "secrets" / "test.seed", per_scene=6)
    assert a.code == 0 and b.code == 0, a.err + b.err
    ha, hb = json.loads(a.out)["manifest_hash"], json.loads(b.out)["manifest_hash"]
    assert ha == hb
    doc = json.loads((tmp_path / "a" / "manifest.json").read_text())
    assert doc["seed"] is None and doc["settings"]["seed"] is None and doc["seed_secret"] is True
    assert doc["seed_sha256"] == hashlib.sha256(text.encode()).hexdigest() == secret.sha256
    data = _all_bytes(tmp_path / "a")
    assert text.encode() not in data and str(secret.seed).encode() not in data
    assert str(secret.seed) not in a.out + a.err
    manifest = read_manifest(tmp_path / "a")
    assert manifest.seed_sha256 == secret.sha256 and manifest.episodes > 0

    # The same seed given openly makes the same episodes (only the manifest differs: it names the seed).
    c = gen(tmp_path / "c", *SMALL, "--seed", secret.seed, per_scene=6)
    assert c.code == 0, c.err
    shards = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*.parquet"))
    assert shards and all((tmp_path / "a" / s).read_bytes() == (tmp_path / "c" / s).read_bytes() for s in shards)
    # Another secret, another data set.
    make_secret_seed(tmp_path / "secrets" / "other.seed")
    d = gen(tmp_path / "d", *SMALL, "--secret-seed-file", tmp_path / "secrets" / "other.seed", per_scene=6)
    assert d.code == 0 and json.loads(d.out)["manifest_hash"] != ha


def test_integer_secret_and_bad_files(tmp_path, gen):
    (tmp_path / "int.seed").write_text("12345\n")
    assert read_secret_seed(tmp_path / "int.seed").seed == 12345
    for name, text in (("short.seed", "abcd"), ("junk.seed", "not a seed"), ("big.seed", str(2**63))):
        (tmp_path / name).write_text(text)
        with pytest.raises(InputError, match=name):
            read_secret_seed(tmp_path / name)
    with pytest.raises(InputError, match="never replaced"):
        make_secret_seed(tmp_path / "int.seed")
    r = gen(tmp_path / "x", *SMALL, "--secret-seed-file", tmp_path / "int.seed", "--seed", "3", per_scene=2)
    assert r.code == 2 and "not both" in r.err and not (tmp_path / "x").exists()
    r = gen(tmp_path / "y", *SMALL, "--secret-seed-file", tmp_path / "junk.seed", per_scene=2)
    assert r.code == 2 and "junk.seed" in r.err and not (tmp_path / "y").exists()
