"""`main-bench train run`'s closing text: how to check and score the submission in its mode, track and goals;
a fresh run says nothing of resuming."""

from __future__ import annotations

import shlex

from main_bench.cli.train import _render, check_command, evaluate_command


def _payload(resumed_from: int) -> dict:
    sub = "runs/my run/submission"
    return {"updates": 3, "agent_steps": 1200, "episodes": 10, "wall_seconds": 4.2, "resumed_from": resumed_from,
            "last": {"success": 0.25, "team_success": 0.5, "spl": 0.1234}, "submission": sub, "mode": "comm",
            "track": "gps", "goal": "point",
            "evaluate_command": evaluate_command(sub, "points", "comm", "gps", "runs/my run/eval", 2, "shared"),
            "check_command": check_command(sub, "comm", "gps", "point", 2)}


def test_a_fresh_run_says_nothing_of_resuming_a_resumed_one_does():
    assert "resumed" not in _render(_payload(0))
    assert "(resumed from update 2)" in _render(_payload(2))


def test_the_closing_text_says_how_to_check_and_evaluate_in_mode_track_and_goals():
    text = _render(_payload(0))
    assert "SPL 0.123" in text and "comm mode, gps track, point goals" in text
    evaluate = next(line for line in text.splitlines() if line.startswith("evaluate it:")).split(":", 1)[1]
    assert shlex.split(evaluate) == ["main-bench", "evaluate", "--episodes", "points", "--split", "val", "--agent",
                                     "runs/my run/submission", "--mode", "comm", "--track", "gps", "--agents",
                                     "2", "--task", "shared", "--out", "runs/my run/eval"]
    check = next(line for line in text.splitlines() if line.startswith("check it:")).split(":", 1)[1]
    assert shlex.split(check) == ["main-bench", "evaluate", "check-agent", "runs/my run/submission", "--mode",
                                  "comm", "--track", "gps", "--goal", "point", "--agents", "2"]
