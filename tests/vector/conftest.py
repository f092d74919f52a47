"""Fixtures of the vector tests: the evaluator tests' tiny data set (point goals, box house, teams of 2)."""

from __future__ import annotations

import pytest
from evaluation.eval_data import session_tiny_dataset


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory):
    """(dataset, cache_dir) of the tiny synthetic data set, shared with the evaluator tests."""
    return session_tiny_dataset(tmp_path_factory)
