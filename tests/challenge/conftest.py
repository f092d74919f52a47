"""Fixtures of the challenge tests: one tiny data set per session, with short episodes (12 steps)."""

from __future__ import annotations

import pytest
from evaluation.eval_data import build_tiny_dataset


@pytest.fixture(scope="session")
def ch_dataset(tmp_path_factory):
    """(dataset, cache_dir) of the tiny synthetic data set with 4 episodes per track of at most 12 steps."""
    root = tmp_path_factory.getbasetemp() / "challenge_data"
    if (root / "dataset" / "manifest.json").is_file():
        return root / "dataset", root / "cache"
    return build_tiny_dataset(root, per_scene=4, max_steps=12)
