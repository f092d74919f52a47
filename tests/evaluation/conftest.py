"""Fixtures of the evaluator tests: one tiny data set per session."""

from __future__ import annotations

import pytest
from eval_data import session_tiny_dataset


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory):
    """(dataset, cache_dir) of the tiny synthetic data set (see eval_data.py)."""
    return session_tiny_dataset(tmp_path_factory)
