"""No command destroys its input: every command that writes an output path refuses one that is an input (the
same path, a symbolic or hard link to it) or a folder holding an input; one line, exit 2, the input untouched.

The table below must name every command with an output (found by walking the CLI), so a new command with an
`--out` and no check fails here. The check comes before any work, so the inputs are small placeholder files.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import typer.main

from main_bench.cli.app import app

# command -> (argv with {in} for the input and {out} for the output, the input is a "file" or a "dir", its name)
CASES: dict[str, tuple[list[str], str, str]] = {
    "stats": (["stats", "{in}", "--out", "{out}", "--no-maps"], "dir", "data"),
    "visualize": (["visualize", "{in}", "--episode", "room/shared/2/0000000", "--out", "{out}"], "dir", "results"),
    "demo": (["demo", "--episodes", "{in}", "--out", "{out}"], "dir", "data"),
    "scenes preview": (["scenes", "preview", "{in}", "--out", "{out}"], "file", "room.obj"),
    "scenes import": (["scenes", "import", "{in}", "--format", "hssd", "--out", "{out}"], "dir", "download"),
    "navmesh build": (["navmesh", "build", "{in}", "--out", "{out}"], "file", "room.glb"),
    "navmesh map": (["navmesh", "map", "{in}", "--out", "{out}"], "file", "nav.npz"),
    "navmesh export": (["navmesh", "export", "{in}", "--out", "{out}"], "file", "nav.npz"),
    "episodes generate": (["episodes", "generate", "--scenes", "{in}", "--out", "{out}"], "file", "room.obj"),
    "episodes export": (["episodes", "export", "{in}", "--out", "{out}"], "dir", "data"),
    "episodes import": (["episodes", "import", "{in}", "--out", "{out}"], "dir", "habitat"),
    "evaluate": (["evaluate", "--episodes", "{in}", "--agent", "baseline:random", "--out", "{out}"], "dir", "data"),
    "leaderboard build": (["leaderboard", "build", "{in}", "--out", "{out}"], "dir", "results"),
    "train run": (["train", "run", "--episodes", "{in}", "--out", "{out}"], "dir", "data"),
    "train point-goals": (["train", "point-goals", "{in}", "--out", "{out}"], "dir", "data"),
    "train export": (["train", "export", "{in}", "--out", "{out}"], "dir", "run"),
}
# Other inputs of the same commands.
MORE = {
    "episodes generate --splits": (["episodes", "generate", "--scenes", "builtin", "--splits", "{in}", "--out",
                                    "{out}"], "file", "splits.json"),
    "episodes generate --navmesh": (["episodes", "generate", "--scenes", "builtin", "--navmesh", "{in}", "--out",
                                     "{out}"], "dir", "navmeshes"),
    "evaluate --agent": (["evaluate", "--episodes", "data", "--agent", "{in}", "--out", "{out}"], "dir", "submission"),
    "evaluate --agent file": (["evaluate", "--episodes", "data", "--agent", "{in}", "--out", "{out}"], "file",
                              "policy.py"),
    "leaderboard build, second results": (["leaderboard", "build", "{in}/../other", "{in}", "--out", "{out}"], "dir",
                                          "results"),
}
#: Commands whose output depends on no input file.
NO_INPUT = {"scenes generate"}


def _commands_with_output() -> set[str]:
    found = set()

    def walk(cmd, path: list[str]) -> None:
        if any(p.name == "out" for p in cmd.params):
            found.add(" ".join(path))
        for name, sub in (getattr(cmd, "commands", None) or {}).items():
            walk(sub, [*path, name])

    walk(typer.main.get_command(app), [])
    return found


def test_every_command_with_an_output_is_checked():
    assert _commands_with_output() == set(CASES) | NO_INPUT


def _make_input(root: Path, kind: str, name: str) -> Path:
    target = root / "work" / name
    target.parent.mkdir(parents=True)
    (root / "work" / "other").mkdir()
    if kind == "dir":
        target.mkdir()
        (target / "keep.json").write_text('{"precious": true}')
    else:
        target.write_text("precious input\n")
    return target


def _snapshot(path: Path) -> dict[str, bytes]:
    if path.is_file():
        return {"": path.read_bytes()}
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def _variants() -> list:
    """Each command with the output as the input itself, a symbolic link to it, a hard link (files only) and the
    folder holding it."""
    return [pytest.param(command, variant, id=f"{command}-{variant}") for command, (_, kind, _) in {**CASES, **MORE}.items()
            for variant in ("same", "symlink", "hardlink", "parent") if not (variant == "hardlink" and kind == "dir")
            and not (variant == "parent" and command.startswith("leaderboard build"))]


@pytest.mark.parametrize(("command", "variant"), _variants())
def test_output_over_an_input_is_refused(cli, tmp_path, monkeypatch, command, variant):
    argv, kind, name = {**CASES, **MORE}[command]
    source = _make_input(tmp_path, kind, name)
    monkeypatch.chdir(source.parent)  # relative inputs (`data` of `evaluate --agent`) resolve beside it
    out = {"same": source, "symlink": tmp_path / f"link-{name}", "hardlink": tmp_path / f"hard-{name}",
           "parent": source.parent}[variant]
    if variant == "symlink":
        out.symlink_to(source)
    elif variant == "hardlink":
        os.link(source, out)
    before = _snapshot(source)
    res = cli(*[a.replace("{in}", str(source)).replace("{out}", str(out)) for a in argv])
    lines = res.err.strip().splitlines()
    assert res.code == 2, (res.code, res.out, res.err)
    assert len(lines) == 1 and "Traceback" not in res.err, res.err
    assert str(out) in lines[0] and "destroy" in lines[0], lines[0]
    assert _snapshot(source) == before


def test_a_report_folder_may_hold_its_results_but_not_where_it_writes(cli, tmp_path):
    """`leaderboard build R/results/x --out R` (the published board's layout) writes only its report files into R;
    a results folder at one of those names would be overwritten and is refused."""
    board = tmp_path / "board"
    for name in ("results", "plots"):
        source = _make_input(board / name, "dir", "results")
        res = cli("leaderboard", "build", str(source), "--out", str(board))
        lines = res.err.strip().splitlines()
        if name == "plots":
            assert res.code == 2 and len(lines) == 1 and "destroy" in lines[0], res.err
        else:
            assert "destroy" not in res.err, res.err


def test_an_output_beside_the_input_is_accepted(tmp_path):
    """The check refuses only what overlaps: an output next to the input, or inside an input folder, passes."""
    from main_bench.io import refuse_output_over_inputs

    source = _make_input(tmp_path, "dir", "data")
    refuse_output_over_inputs(tmp_path / "work" / "stats", {"DATASET": source})
    refuse_output_over_inputs(source / "habitat", {"DATASET": source})
    refuse_output_over_inputs(source, {"missing": tmp_path / "nowhere", "none": None})
