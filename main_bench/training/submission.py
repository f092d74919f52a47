"""A trained run as a submission directory that `main-bench evaluate` loads unchanged.

Flows in: the trained `Net` and the run's settings. Flows out, in one folder: `policy.py` (`make_policy(root,
seed)` giving one agent's `AgentPolicy`), `model.py` and `obs.py` (copies of this package's self-contained model
and observation packing, so the policy process needs only numpy and torch), `weights.pt` (model config and
state_dict) and `metadata.json` (the exact command, the toolkit's commit, algorithm, evaluation mode,
agent-steps, updates, wall time, the training data's manifest hash; paths relative to the project root, never
the machine's absolute layout).
"""

from __future__ import annotations

import io
import shutil
from pathlib import Path
from typing import Any

from ..io import atomic_write_bytes, atomic_write_json, atomic_write_text
from ..portable import manifest_hash, portable_command, portable_path, project_root

METADATA_VERSION = 1
#: model.py's import of the observation packing, as written in the package and in a submission's copy.
SIBLING_IMPORT = ("from ..vector.obs import ", "from obs import ")
WEIGHTS = "weights.pt"

POLICY_PY = '''"""A main-bench agent policy trained with `main-bench train` ({algo}); run it with --mode {mode}.

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
'''


def write_submission(folder: str | Path, net: Any, settings: Any, command: str, *, agent_steps: int, updates: int,
                     wall_seconds: float, commit: str = "") -> Path:
    """Write the submission folder (see the module docstring); returns it. `commit`: the toolkit's commit the
    run trained with (`leaderboard.provenance.toolkit_commit`)."""
    import torch

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    here = Path(__file__).resolve().parent
    shutil.copyfile(here.parent / "vector" / "obs.py", folder / "obs.py")
    model = (here / "model.py").read_text(encoding="utf-8")
    atomic_write_text(folder / "model.py", model.replace(SIBLING_IMPORT[0], SIBLING_IMPORT[1], 1))
    atomic_write_text(folder / "policy.py", POLICY_PY.format(algo=settings.algo, mode=settings.mode))
    state = {"config": net.config.to_dict(), "model": {k: v.detach().cpu() for k, v in net.state_dict().items()}}
    buffer = io.BytesIO()
    torch.save(state, buffer)
    atomic_write_bytes(folder / WEIGHTS, buffer.getvalue())
    root = project_root()
    plain = settings.to_dict()
    atomic_write_json(folder / "metadata.json", {
        "schema_version": METADATA_VERSION, "command": portable_command(command, root), "commit": commit,
        "algo": settings.algo,
        "mode": settings.mode, "agent_steps": int(agent_steps), "updates": int(updates),
        "wall_seconds": round(float(wall_seconds), 1), "model": net.config.to_dict(),
        "settings": {**plain, "episodes": portable_path(settings.episodes, root),
                     "cache_dir": None if plain.get("cache_dir") is None else portable_path(plain["cache_dir"], root)},
        "episodes_manifest_hash": manifest_hash(settings.episodes),
    })
    return folder


def export_checkpoint(run_dir: str | Path, folder: str | Path, command: str = "") -> Path:
    """Write the submission of a run's last checkpoint (`run_dir/checkpoint.pt`) to `folder`; returns it."""
    import torch

    from ..errors import InputError
    from .model import ModelConfig, Net
    from .ppo import PPOSettings
    from .settings import TrainSettings

    path = Path(run_dir) / "checkpoint.pt"
    if not path.is_file():
        raise InputError(f"{path}: no checkpoint; train first (main-bench train run --out {run_dir})")
    state = torch.load(path, map_location="cpu", weights_only=False)
    net = Net(ModelConfig(**state["config"]))
    net.load_state_dict(state["model"])
    settings = TrainSettings(**{**state["settings"], "ppo": PPOSettings(**state["settings"]["ppo"])})
    return write_submission(folder, net, settings, command or f"checkpoint of {run_dir}",
                            agent_steps=state["agent_steps"], updates=state["update"],
                            wall_seconds=state["wall_seconds"], commit=str(state.get("commit", "")))
