"""Reading a data set's episode keys without pandas (`episode_scenes`, `parquet_read.read_values`)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mb_testing import REPO

from main_bench.episodes.dataset import episode_scenes, load_table, read_manifest
from main_bench.errors import DatasetError
from main_bench.parquet_read import read_values

SAMPLE = REPO / "episodes" / "sample"


def test_episode_scenes_are_load_table_s_two_columns_for_every_track():
    manifest = read_manifest(SAMPLE)
    tracks = sorted({(s.split, s.task, s.agents) for s in manifest.shards})
    assert len(tracks) == 18
    for split, task, agents in tracks:
        table = load_table(SAMPLE, split, task, agents)
        ids, scenes = episode_scenes(manifest, split, task, agents)
        assert ids == table.column("episode_id").to_pylist() and len(ids) > 0
        assert scenes == table.column("scene_id").to_pylist()


def test_episode_scenes_load_neither_pandas_nor_pyarrow_s_dataset_reader():
    code = ("import json, sys\n"
            "from main_bench.episodes.dataset import episode_scenes, read_manifest\n"
            f"ids, scenes = episode_scenes(read_manifest({str(SAMPLE)!r}), 'val', 'shared', 2)\n"
            "print(json.dumps([len(ids), [m for m in ('pandas', 'pyarrow.dataset') if m in sys.modules]]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    count, loaded = json.loads(res.stdout)
    assert count == 40 and loaded == []


def test_episode_scenes_refuse_a_shard_that_differs_from_its_checksum(tmp_path):
    copy = tmp_path / "sample"
    shutil.copytree(SAMPLE, copy)
    manifest = read_manifest(copy)
    shard = next(s for s in manifest.shards if (s.split, s.task, s.agents) == ("val", "shared", 2))
    (copy / shard.path).write_bytes((copy / shard.path).read_bytes()[:-100])
    with pytest.raises(DatasetError, match="differs from its checksum") as err:
        episode_scenes(manifest, "val", "shared", 2)
    assert err.value.path == copy / shard.path


def test_read_values_concatenates_files_in_order_and_names_a_bad_file(tmp_path):
    first, second, other, cut = (tmp_path / f"{n}.parquet" for n in ("a", "b", "other", "cut"))
    pq.write_table(pa.table({"k": ["x", "y"], "n": [1, 2]}), first)
    pq.write_table(pa.table({"k": ["z"], "n": [3]}), second)
    pq.write_table(pa.table({"j": ["w"]}), other)
    cut.write_bytes(first.read_bytes()[:-20])
    assert read_values([second, first], ["k", "n"], error=DatasetError, fix="fix it") == {
        "k": ["z", "x", "y"], "n": [3, 1, 2]}
    assert read_values([], ["k"], error=DatasetError, fix="fix it") == {"k": []}
    with pytest.raises(DatasetError, match=r"lacks column\(s\) \['k'\]; fix it") as err:
        read_values([first, other], ["k"], error=DatasetError, fix="fix it")
    assert err.value.path == other
    with pytest.raises(DatasetError, match="unreadable Parquet file .*; fix it") as err:
        read_values([first, cut], ["k"], error=DatasetError, fix="fix it")
    assert err.value.path == cut
