"""Vectorised multi-agent sampling: B sub-environments of an N-agent team in worker processes or Ray actors."""
