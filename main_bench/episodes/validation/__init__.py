"""Checking a data set: the conformance checks, `--recheck`, and the report of what they found."""
