"""Every damaged input of every command that reads it: exit 2, one line on stderr naming the file, no traceback,
and the output already written there intact.

The corpus: each input file kind (episode shards, manifest, Habitat export, results parts and summary.json,
navmesh file, GLB/OBJ/PLY scenes, split file, submission files) x each damage (truncated, bit-flipped, empty)
x each command reading it. Inputs are made once per module (`corpus.py`); each case damages a private copy.
`episodes validate` is a checker: a damaged shard is a failed check (exit 1, its report names the shard);
a damaged manifest is bad input (exit 2) as everywhere else.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from corpus import DAMAGES, build_pristine, snapshot

SHARD = "data/split=val/task=shared/agents=2/part-00000.parquet"
RECORDS = "results/records/split=val/task=shared/agents=2/part-00000.parquet"
TRAJ = "results/trajectories/split=val/task=shared/agents=2/part-00000.parquet"
EPISODE = "room/shared/2/0000000"

# Commands by the input they read: (name, argv with {r} for the case folder, output that must stay intact).
DATASET_COMMANDS = [
    ("validate", ["episodes", "validate", "{r}/data"], None),
    ("export", ["episodes", "export", "{r}/data", "--out", "{r}/habitat"], "habitat"),
    ("evaluate", ["evaluate", "--episodes", "{r}/data", "--split", "val", "--agent", "baseline:random",
                  "--out", "{r}/results", "--no-progress"], "results"),
    ("stats", ["stats", "{r}/data", "--out", "{r}/stats", "--no-maps"], "stats"),
]
RESULTS_COMMANDS = [
    ("leaderboard", ["leaderboard", "build", "{r}/results", "--out", "{r}/board", "--no-plots"], "board"),
    ("visualize", ["visualize", "{r}/results", "--episode", EPISODE, "--out", "{r}/board/episode.png"], "board"),
]
NAVMESH_COMMANDS = [
    ("info", ["navmesh", "info", "{r}/nav.npz"], None),
    ("distance", ["navmesh", "distance", "{r}/nav.npz", "--from", "1,1,0", "--to", "4,4,0"], None),
    ("path", ["navmesh", "path", "{r}/nav.npz", "--from", "1,1,0", "--to", "4,4,0"], None),
    ("map", ["navmesh", "map", "{r}/nav.npz", "--out", "{r}/board/map.png"], "board"),
    ("export", ["navmesh", "export", "{r}/nav.npz", "--out", "{r}/board/surface.obj"], "board"),
]
SCENE_COMMANDS = [
    ("info", ["scenes", "info", "{r}/scenes/room.{s}"], None),
    ("preview", ["scenes", "preview", "{r}/scenes/room.{s}", "--out", "{r}/board/preview.png"], "board"),
    ("navmesh-build", ["navmesh", "build", "{r}/scenes/room.{s}", "--out", "{r}/nav.npz"], "nav.npz"),
]
SPLITS_COMMANDS = [
    ("generate", ["episodes", "generate", "--scenes", "{r}/scenes/room.obj", "--splits", "{r}/splits.json",
                  "--out", "{r}/data", "--up", "z", "--per-scene", "2"], "data"),
]
SUBMISSION_COMMANDS = [
    ("evaluate", ["evaluate", "--episodes", "{r}/data", "--split", "val", "--agent", "{r}/submission",
                  "--out", "{r}/fresh", "--limit", "1", "--no-progress"], None),
    ("check-agent", ["evaluate", "check-agent", "{r}/submission"], None),
]
HABITAT_COMMANDS = [
    ("import", ["episodes", "import", "{r}/habitat", "--out", "{r}/data", "--overwrite"], "data"),
]


def _cases() -> list:
    cases = []
    inputs = [
        ("shard", SHARD, DATASET_COMMANDS), ("manifest", "data/manifest.json", DATASET_COMMANDS),
        ("records", RECORDS, RESULTS_COMMANDS), ("trajectories", TRAJ, RESULTS_COMMANDS[1:]),
        ("summary", "results/summary.json", RESULTS_COMMANDS), ("navmesh", "nav.npz", NAVMESH_COMMANDS),
        ("splits", "splits.json", SPLITS_COMMANDS),
        ("habitat", "habitat/shared_n2/val/val.json.gz", HABITAT_COMMANDS),
        *[(f"scene-{s}", f"scenes/room.{s}", [(n, [a.replace("{s}", s) for a in argv], o)
                                               for n, argv, o in SCENE_COMMANDS]) for s in ("glb", "obj", "ply")],
    ]
    for kind, rel, commands in inputs:
        for damage in DAMAGES:
            for name, argv, out in commands:
                code = 1 if (kind == "shard" and name == "validate") else 2
                cases.append(pytest.param(rel, damage, argv, out, code, rel, id=f"{kind}-{damage}-{name}"))
    # A submission is a folder: its errors name the folder (the policy's own code reads its weights).
    for kind, rel in (("policy", "submission/policy.py"), ("weights", "submission/weights.npy")):
        for damage in [*DAMAGES, "missing"]:
            for name, argv, out in SUBMISSION_COMMANDS:
                # check-agent reports a submission that does not load as its failed `loads` check (exit 1).
                code = 1 if name == "check-agent" and (kind, damage) != ("policy", "missing") else 2
                cases.append(pytest.param(rel, damage, argv, out, code, "submission", id=f"{kind}-{damage}-{name}"))
    return cases


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    root = build_pristine(tmp_path_factory.mktemp("pristine"))
    board = root / "board"
    board.mkdir()
    (board / "episode.png").write_bytes(b"an earlier picture")
    (board / "map.png").write_bytes(b"an earlier map")
    (board / "preview.png").write_bytes(b"an earlier preview")
    (root / "stats").mkdir()
    (root / "stats" / "stats.json").write_text("{}")
    return root


def _check_one_line(res, named: str, code: int) -> None:
    lines = res.err.strip().splitlines()
    assert res.code == code, (res.code, res.err[-2000:])
    assert "Traceback" not in res.err and "Traceback" not in res.out
    if code == 2:
        assert len(lines) == 1, res.err
        assert named in lines[0], (named, lines[0])
    else:  # a failed check: the report on stdout names the file
        assert named in res.out, res.out


@pytest.mark.parametrize(("rel", "damage", "argv", "out", "code", "named"), _cases())
def test_damaged_input(cli, pristine, tmp_path, rel, damage, argv, out, code, named):
    root = tmp_path / "case"
    shutil.copytree(pristine, root)
    target = root / rel
    if damage == "missing":
        target.unlink()
    else:
        DAMAGES[damage](target)
    before = snapshot(root / out) if out else {}
    res = cli(*[a.replace("{r}", str(root)) for a in argv])
    _check_one_line(res, str(root / named) if code == 2 else named.rsplit("/", 1)[-1], code)
    if out:
        assert snapshot(root / out) == before, f"{out} changed"


RESUME = ["evaluate", "--episodes", "{d}/data", "--split", "val", "--agent", "baseline:random", "--out", "{r}/run",
          "--limit", "1", "--no-progress"]


@pytest.fixture(scope="module")
def evaluated(pristine, tmp_path_factory) -> Path:
    """The pristine inputs plus a finished evaluation (`run/`) of the random baseline, one episode per track."""
    from main_bench.cli.app import main

    root = tmp_path_factory.mktemp("evaluated") / "case"
    shutil.copytree(pristine, root)
    assert main([a.replace("{r}", str(root)).replace("{d}", str(root)) for a in RESUME]) == 0
    return root


@pytest.mark.parametrize("damage", list(DAMAGES))
@pytest.mark.parametrize("kind", ["records", "trajectories"])
def test_resumed_evaluation_with_a_damaged_part(cli, evaluated, tmp_path, kind, damage):
    """A finished chunk's part file damaged after the run: resuming names it and changes nothing."""
    root = tmp_path / "case"  # the run is copied; the data set stays where the run's identity says it is
    shutil.copytree(evaluated / "run", root / "run")
    target = next(iter(sorted((root / "run" / kind).rglob("part-*.parquet"))))
    DAMAGES[damage](target)
    before = snapshot(root / "run")
    res = cli(*[a.replace("{r}", str(root)).replace("{d}", str(evaluated)) for a in RESUME])
    _check_one_line(res, str(target), 2)  # the chunk ledger's hash, or the reader, names the part
    assert snapshot(root / "run") == before
