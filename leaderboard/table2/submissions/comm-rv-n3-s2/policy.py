"""A main-bench agent policy trained with `main-bench train` (comm-rv); run it with --mode comm.

`make_policy(root, seed)` loads `weights.pt` from this folder into the model of `model.py` and returns one
agent's policy: `reset(info)`, `act(observation, inbox) -> (action, message)`. metadata.json says how it was
trained (command, agent-steps, wall time).
"""

from pathlib import Path

import torch
from model import TrainedAgent, load_net

torch.set_num_threads(1)


def make_policy(root, seed=0):
    """One agent of the trained team."""
    state = torch.load(Path(root) / "weights.pt", map_location="cpu", weights_only=True)
    return TrainedAgent(load_net(state), seed)
