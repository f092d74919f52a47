"""Close matches for mistyped names."""

from __future__ import annotations

from main_bench.suggest import close_matches, did_you_mean


def test_close_matches_best_first_and_only_close_ones():
    assert close_matches("randon", ["oracle", "random", "comm"]) == ["random"]
    assert close_matches("zzz", ["oracle", "random"]) == []
    assert close_matches("ep-0001", ["ep-0001x", "ep-0002", "ep-0003", "ep-0004"], n=2) == ["ep-0001x", "ep-0002"]


def test_did_you_mean_phrases_one_or_several_or_nothing():
    assert did_you_mean("randon", ["random", "oracle"], "baseline:") == "; did you mean baseline:random?"
    assert did_you_mean("ep-1", ["ep-2", "ep-3"]) == "; did you mean ep-2 or ep-3?"
    assert did_you_mean("ep-1", ["ep-2", "ep-3", "ep-4", "ep-5"], n=3) == "; did you mean ep-2, ep-3 or ep-4?"
    assert did_you_mean("qqq", ["random"]) == ""
