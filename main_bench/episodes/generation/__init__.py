"""Generating a data set: the work plan, the sampler, shard files, the executors, the scene sources, secret seeds."""
