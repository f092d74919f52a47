"""Episode ids findable from the CLI: `episodes list` on the committed sample, filtered, limited, as text and
JSON; a filter value the data set lacks is one line naming what it has."""

from __future__ import annotations

import json

import pytest
from mb_testing import REPO

from main_bench.episodes.dataset import load_table
from main_bench.episodes.listing import EpisodeFilter, list_episodes
from main_bench.errors import DatasetError, InputError

SAMPLE = REPO / "episodes" / "sample"


def test_the_listing_is_the_data_set_filtered_in_order():
    listing = list_episodes(SAMPLE, EpisodeFilter(split="val", task="shared", agents=3))
    table = load_table(SAMPLE, "val", "shared", 3).to_pylist()
    assert listing.matched == len(listing.entries) == len(table) > 0
    by_id = {row["episode_id"]: row for row in table}
    assert [e.episode_id for e in listing.entries] == sorted(by_id)
    for e in listing.entries:
        row = by_id[e.episode_id]
        assert (e.split, e.task, e.agents, e.scene_id) == ("val", "shared", 3, row["scene_id"])
        assert e.geodesic_distances == pytest.approx(row["geodesic_distances"], abs=1e-3)
        assert len(e.targets) == 3 and len(set(e.targets)) == 1  # one target for the team
    scene = listing.entries[0].scene_id
    one_scene = list_episodes(SAMPLE, EpisodeFilter(scene=scene, limit=4))
    assert len(one_scene.entries) == 4 and one_scene.matched > 4
    assert {e.scene_id for e in one_scene.entries} == {scene}
    assert list_episodes(SAMPLE).matched == len(load_table(SAMPLE))


@pytest.mark.parametrize(("selection", "words"), [
    (EpisodeFilter(split="vla"), "no split 'vla' in this data set; did you mean val?"),
    (EpisodeFilter(scene="house_00O5"), "did you mean house_0005"),
    (EpisodeFilter(agents=9), "team sizes: 2, 3, 4"),
])
def test_a_value_the_data_set_lacks_names_what_it_has(selection, words):
    with pytest.raises(DatasetError) as err:
        list_episodes(SAMPLE, selection)
    assert words in str(err.value) and str(SAMPLE) in str(err.value)


def test_a_bad_task_is_bad_input():
    with pytest.raises(InputError, match="--task must be shared, individual or both"):
        list_episodes(SAMPLE, EpisodeFilter(task="all"))


def test_cli_text_and_json(cli):
    r = cli("episodes", "list", SAMPLE, "--split", "val", "--agents", "2", "--task", "individual", "--limit", "3")
    assert r.code == 0, r.err
    lines = r.out.strip().splitlines()
    assert lines[0].split()[:2] == ["episode", "id"] and "geodesic" in lines[0]
    assert len(lines) == 5 and lines[-1].startswith("3 of ") and "--limit 0" in lines[-1]
    assert all(line.split()[1:4] == ["val", "individual", "2"] for line in lines[1:4])
    r = cli("episodes", "list", SAMPLE, "--split", "val", "--agents", "2", "--task", "both", "--limit", "0", "--json")
    doc = json.loads(r.out)
    assert doc["schema_version"] == 1 and doc["command"] == "episodes list"
    assert len(doc["episodes"]) == doc["matched"] == len(load_table(SAMPLE, "val", None, 2))
    assert set(doc["episodes"][0]) == {"episode_id", "split", "task", "agents", "scene_id", "geodesic_distances",
                                       "targets"}
    r = cli("episodes", "list", SAMPLE, "--split", "vla")
    assert r.code == 2 and r.err.count("\n") == 1 and "did you mean val?" in r.err
