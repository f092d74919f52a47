"""The processes a command runs in besides the console script's own: the opt-in warm command server (`warm` is
its client, `warm_server` the server) and one job of the challenge queue (`job`)."""
