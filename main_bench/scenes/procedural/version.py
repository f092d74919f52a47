"""The built-in house generator's version: part of every house's sidecar, so a cached house made by another
version is generated again. Bumped whenever the same seed would give a different house."""

GENERATOR_VERSION = "1.2.0"
