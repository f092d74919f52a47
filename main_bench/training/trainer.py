"""The training loop: sample a rollout from the vectorised sampler, compute GAE, run PPO, log, checkpoint.

Flows in: `TrainSettings` and a run folder. Flows out, in the run folder: `checkpoint.pt` (every K updates and
at exit; a run started again on the same folder resumes from it, also after a SIGKILL), `curve.csv` and
`curve.png` (return, success and SPL, episode length, rate of `found` calls against agent-steps), TensorBoard
events under `tb/` when `tensorboard` is installed, and `submission/` (`submission.write_submission`), which
`main-bench evaluate` scores unchanged. The progress callback gets one line per update (`monitor.progress_line`).
"""

from __future__ import annotations

import io
import signal
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io import atomic_write_bytes
from ..vector.layout import EPISODE_STATS, VecSpec
from .curves import CURVE_COLUMNS, read_curve, write_curve
from .gae import gae
from .monitor import found_rate, progress_line, time_status
from .settings import TrainSettings
from .storage import Rollout, StorageShape

CHECKPOINT = "checkpoint.pt"
CHECKPOINT_VERSION = 2
WINDOW = 50  # episodes in the curve's moving averages
RATE_WINDOW = 20  # updates whose median wall time sets the progress line's time left


@dataclass(frozen=True)
class TrainSummary:
    """What a run did: updates and agent-steps in total, episodes, wall seconds of this process, the last curve
    row, the time split (seconds) of this process, where things are, whether it resumed."""

    updates: int
    agent_steps: int
    episodes: int
    wall_seconds: float
    last: dict[str, float]
    timing: dict[str, float]
    run_dir: str
    submission: str
    resumed_from: int
    losses: list[dict[str, float]]


def model_config(settings: TrainSettings) -> Any:
    """The `ModelConfig` of a run."""
    from .model import ModelConfig, message_floats_for

    return ModelConfig(algo=settings.algo, agents=settings.agents, image_size=settings.image_size,
                       use_rgb=settings.use_rgb, hidden=settings.hidden, features=settings.features,
                       message_floats=message_floats_for(settings.algo, settings.hidden, settings.features))


def vec_spec(settings: TrainSettings, seed: int) -> VecSpec:
    """The sampler of a run, seeded with `seed`."""
    cfg = model_config(settings)
    return VecSpec(episodes=settings.episodes, split=settings.split, agents=settings.agents,
                   num_envs=settings.num_envs, task=settings.task, goal=settings.goal, track=settings.track,
                   image_size=settings.image_size, use_rgb=settings.use_rgb, message_floats=cfg.message_floats,
                   seed=seed, max_steps=settings.max_steps, renderer=settings.renderer,
                   found_penalty=settings.found_penalty, cache_dir=settings.cache_dir,
                   step_penalty=settings.step_penalty, success_bonus=settings.success_bonus,
                   gpu=settings.render_device)


class Trainer:
    """One run in `run_dir` (see the module docstring); `run()` trains until the budget and writes everything."""

    def __init__(self, settings: TrainSettings, run_dir: str | Path, command: str = "",
                 progress: Callable[[str], None] | None = None) -> None:
        import torch

        from ..leaderboard.provenance import toolkit_commit
        from .model import Net

        self.settings, self.run_dir, self.command = settings, Path(run_dir), command
        #: The code this process trains with (a resumed run records the commit it resumed on).
        self.commit = toolkit_commit()
        self.progress = progress
        self.run_dir.mkdir(parents=True, exist_ok=True)
        if settings.device.startswith("cuda") and not torch.cuda.is_available():
            raise InputError(f"--device {settings.device}: torch sees no CUDA device; use --device cpu")
        self.device = settings.device
        torch.manual_seed(settings.seed)
        self.net = Net(model_config(settings)).to(self.device)
        self.net.bf16 = settings.bf16
        self._rollout: Rollout | None = None
        self.optimizer = torch.optim.Adam(self.net.parameters(), lr=settings.ppo.lr, eps=1e-5)
        self.update, self.agent_steps, self.episodes, self.wall_before = 0, 0, 0, 0.0
        self.curve: list[dict[str, float]] = []
        self.window: deque[np.ndarray] = deque(maxlen=WINDOW)
        self.resumed_from = self._resume()
        self._stop = False

    # -- checkpoints --------------------------------------------------------------------------------------------

    def _resume(self) -> int:
        import torch

        path = self.run_dir / CHECKPOINT
        if not path.is_file():
            return 0
        try:
            state = torch.load(path, map_location=self.device, weights_only=False)
        except Exception as exc:
            raise InputError(f"{path}: unreadable checkpoint ({type(exc).__name__}: {exc}); delete it to start "
                             "over") from None
        if state.get("version") != CHECKPOINT_VERSION or state.get("config") != model_config(self.settings).to_dict():
            raise InputError(f"{path}: checkpoint of another model or version ({state.get('config')}); use a "
                             "new --out folder or the same settings")
        self.net.load_state_dict(state["model"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.update, self.agent_steps = int(state["update"]), int(state["agent_steps"])
        self.episodes, self.wall_before = int(state["episodes"]), float(state["wall_seconds"])
        self.window.extend(np.asarray(w) for w in state["window"])
        self.curve = [row for row in read_curve(self.run_dir / "curve.csv") if row["update"] <= self.update]
        return self.update

    def checkpoint(self, wall: float) -> None:
        """Write the curve, then `checkpoint.pt` atomically (model, optimiser, counters, the curve's episode window).

        In that order, a run killed between the two writes leaves a curve with every row the checkpoint counts
        (a resumed run drops rows past the checkpoint's update); the other order could lose the last rows."""
        import torch

        write_curve(self.run_dir, self.curve)

        state = {"version": CHECKPOINT_VERSION, "config": model_config(self.settings).to_dict(),
                 "settings": self.settings.to_dict(), "model": self.net.state_dict(),
                 "optimizer": self.optimizer.state_dict(), "update": self.update, "agent_steps": self.agent_steps,
                 "episodes": self.episodes, "wall_seconds": wall, "window": [w.tolist() for w in self.window],
                 "commit": self.commit}
        buffer = io.BytesIO()
        torch.save(state, buffer)
        atomic_write_bytes(self.run_dir / CHECKPOINT, buffer.getvalue())

    # -- the loop -----------------------------------------------------------------------------------------------

    def run(self) -> TrainSummary:
        """Train until `updates` or `max_minutes`; checkpoint, write curves and the submission; summary."""
        import torch

        from ..vector.sampler import make_sampler
        from .submission import write_submission

        s = self.settings
        start = self._tick = time.perf_counter()
        # After a resume the sub-environments restart from fresh episodes, seeded by the update reached.
        sampler = make_sampler(vec_spec(s, s.seed + 7919 * self.update), s.backend, s.workers)
        timing = {"sample": 0.0, "forward": 0.0, "update": 0.0}
        losses: list[dict[str, float]] = []
        old = {sig: signal.getsignal(sig) for sig in (signal.SIGTERM, signal.SIGINT)}
        for sig in old:
            signal.signal(sig, self._on_signal)
        tb = _tensorboard(self.run_dir)
        update_threads = torch.get_num_threads()
        # While a half steps in its workers, the forward of the other half shares the cores with them: one torch
        # thread then, since threads waiting on each other stall when the cores are oversubscribed.
        collect_threads = 1 if s.backend != "inline" else update_threads
        first_update = self.update
        recent: deque[float] = deque(maxlen=RATE_WINDOW)  # wall seconds of the last updates, for the time left
        try:
            arrays = sampler.reset()
            hidden = np.zeros((s.num_envs, s.agents, s.hidden), dtype=np.float32)
            while self.update < s.updates and not self._stop:
                if s.max_minutes and (time.perf_counter() - start) / 60.0 >= s.max_minutes:
                    break
                torch.set_num_threads(collect_threads)
                rollout, hidden, ended = self._collect(sampler, arrays, hidden, timing)
                torch.set_num_threads(update_threads)
                found = found_rate(rollout.data)
                t0 = time.perf_counter()
                loss = self._learn(rollout)
                timing["update"] += time.perf_counter() - t0
                losses.append(loss)
                self.update += 1
                previous_tick = self._tick  # the end of the last update (`_curve_row` moves it to now)
                row = self._curve_row(ended, time.perf_counter() - start, loss, found)
                recent.append(self._tick - previous_tick)
                self.curve.append(row)
                if tb is not None:
                    for key, value in row.items():
                        tb.add_scalar(key, value, int(row["agent_steps"]))
                if self.progress:
                    times = time_status(self._tick - start, s.max_minutes, self.update - first_update,
                                        s.updates - self.update, recent)
                    self.progress(progress_line(row, s.updates, times))
                if self.update % s.checkpoint_every == 0:
                    self.checkpoint(self.wall_before + time.perf_counter() - start)
        finally:
            sampler.close()
            torch.set_num_threads(update_threads)
            for sig, handler in old.items():
                signal.signal(sig, handler)
            if tb is not None:
                tb.close()
        wall = time.perf_counter() - start
        self.checkpoint(self.wall_before + wall)
        sub = write_submission(self.run_dir / "submission", self.net, s, self.command,
                               agent_steps=self.agent_steps, updates=self.update,
                               wall_seconds=self.wall_before + wall, commit=self.commit)
        return TrainSummary(updates=self.update, agent_steps=self.agent_steps, episodes=self.episodes,
                            wall_seconds=wall, last=self.curve[-1] if self.curve else {}, timing=timing,
                            run_dir=str(self.run_dir), submission=str(sub), resumed_from=self.resumed_from,
                            losses=losses)

    def _on_signal(self, signum: int, frame: Any) -> None:
        self._stop = True

    def _collect(self, sampler: Any, arrays: dict[str, np.ndarray], hidden: np.ndarray,
                 timing: dict[str, float]) -> tuple[Rollout, np.ndarray, list[np.ndarray]]:
        """One rollout. The sampler's two halves (`sampler.groups`) are pipelined: while one half steps (in its
        workers), the policy computes the other half's actions. Actions are drawn by inverse CDF from one
        uniform number per agent-step, drawn for the whole rollout up front, so the draws do not depend on the
        order in which the halves arrive."""
        import torch

        s = self.settings
        b, n = s.num_envs, s.agents
        if self._rollout is None:  # every field is written again each rollout: one buffer serves every update
            self._rollout = Rollout(StorageShape(s.rollout, b, n, s.image_size, s.use_rgb, s.hidden,
                                                 max(self.net.config.message_floats, 1)),
                                    pinned=self.device.startswith("cuda"))
        rollout = self._rollout
        gen = torch.Generator().manual_seed(s.seed * 1_000_003 + self.update)
        draws = torch.rand((s.rollout, b, n), generator=gen, dtype=torch.float64).numpy()
        groups = [slice(rows[0], rows[-1] + 1) for rows in sampler.groups]
        acted = np.zeros((b, n), dtype=bool)
        ended: list[np.ndarray] = []
        for t in range(s.rollout + 1):
            for g, rows in enumerate(groups):
                if t > 0:
                    t0 = time.perf_counter()
                    sampler.wait(g)
                    timing["sample"] += time.perf_counter() - t0
                    self._outcome(rollout, t - 1, rows, arrays, acted, ended)
                t0 = time.perf_counter()
                hidden[rows] *= ~arrays["first"][rows][..., None]
                logits, new_hidden, message, values = self._forward(arrays, rows, hidden[rows])
                if t == s.rollout:  # bootstrap values of the state after the rollout
                    rollout.data["values"][t, rows] = values
                    timing["forward"] += time.perf_counter() - t0
                    continue
                probs = _softmax(logits)
                actions = (np.cumsum(probs, axis=1)[:, :-1] <= draws[t, rows].reshape(-1, 1)).sum(axis=1)
                logp = np.log(np.maximum(probs[np.arange(len(actions)), actions], 1e-12)).astype(np.float32)
                shape = (rows.stop - rows.start, n)
                rollout.put_observation(t, arrays, rows)
                rollout.put_action(t, rows, hidden[rows], actions.reshape(shape), logp.reshape(shape), values)
                arrays["actions"][rows] = actions.reshape(shape)
                if message is not None:
                    arrays["messages"][rows, :, : message.shape[-1]] = message.reshape(*shape, -1)
                acted[rows] = arrays["alive"][rows]
                hidden[rows] = new_hidden
                timing["forward"] += time.perf_counter() - t0
                t0 = time.perf_counter()
                sampler.send(g)
                timing["sample"] += time.perf_counter() - t0
        return rollout, hidden, ended

    def _forward(self, arrays: dict[str, np.ndarray], rows: slice, hidden: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
        """The policy on `rows` of the sampler's arrays from memories `hidden` (b, N, H): logits (b * N, 4),
        new memories (b, N, H), messages (b * N, F) or None, values (b, N); numpy, on the host."""
        import torch

        from .model import to_tensors

        net, dev = self.net, self.device
        cfg = net.config
        b, n = hidden.shape[:2]
        with torch.no_grad():
            d, r, v = to_tensors(arrays["depth"][rows], arrays["rgb"][rows] if "rgb" in arrays else None,
                                 arrays["vec"][rows], dev)
            h = torch.from_numpy(np.ascontiguousarray(hidden).reshape(b * n, -1)).to(dev)
            messages = lengths = None
            if cfg.comm:
                messages = torch.from_numpy(arrays["inbox"][rows, ..., : cfg.message_floats]).flatten(0, 1).to(dev)
                lengths = torch.from_numpy(arrays["inbox_len"][rows]).flatten(0, 1).to(dev)
            logits, h_new, message = net.step(d, r, v, h, messages, lengths)
            alive = torch.from_numpy(arrays["alive"][rows]).to(dev).float()
            values = net.value(h_new.reshape(b, n, -1), alive).cpu().numpy()
        return (logits.float().cpu().numpy(), h_new.cpu().numpy().reshape(b, n, -1),
                None if message is None else message.cpu().numpy(), values)

    def _outcome(self, rollout: Rollout, t: int, rows: slice, arrays: dict[str, np.ndarray], acted: np.ndarray,
                 ended: list[np.ndarray]) -> None:
        """Store step t's rewards and dones of `rows` once their step is in; count agent-steps and ended episodes."""
        reward = arrays["reward"][rows].copy()
        if self.settings.team_reward:
            reward = np.repeat(reward.sum(axis=1, keepdims=True), reward.shape[1], axis=1)
        rollout.put_outcome(t, rows, reward, arrays["done"][rows])
        self.agent_steps += int(acted[rows].sum())
        for row in np.flatnonzero(arrays["stats"][rows, 0] > 0):
            ended.append(arrays["stats"][rows.start + row].copy())

    def _learn(self, rollout: Rollout) -> dict[str, float]:
        from .ppo import ppo_update

        p, d = self.settings.ppo, rollout.data
        advantages, returns = gae(d["rewards"], d["values"], d["done"], d["alive"], p.gamma, p.gae_lambda)
        rng = np.random.default_rng([self.settings.seed, self.update])
        self.net.train()
        out = ppo_update(self.net, self.optimizer, d, advantages, returns, p, rng, self.device)
        self.net.eval()
        return out

    def _curve_row(self, ended: list[np.ndarray], seconds: float, loss: dict[str, float],
                   found: float) -> dict[str, float]:
        self.episodes += len(ended)
        self.window.extend(ended)
        averages = np.array(self.window).mean(axis=0) if self.window else np.full(len(EPISODE_STATS), np.nan)
        mean = dict(zip(EPISODE_STATS, averages, strict=True))
        previous = self.curve[-1]["agent_steps"] if self.curve else 0
        row = {"update": float(self.update), "agent_steps": float(self.agent_steps),
               "episodes": float(self.episodes), "wall_seconds": self.wall_before + seconds,
               "reward": float(mean["ep_return"]), "team_success": float(mean["ep_team_success"]),
               "success": float(mean["ep_success"]), "spl": float(mean["ep_spl"]),
               "episode_length": float(mean["ep_length"]), "found_rate": found, **loss}
        now = time.perf_counter()
        row["steps_per_second"] = (self.agent_steps - previous) / max(now - self._tick, 1e-9)
        self._tick = now
        return {k: row.get(k, float("nan")) for k in CURVE_COLUMNS}


def _softmax(logits: np.ndarray) -> np.ndarray:
    """Row-wise softmax in float64 (the action draw's CDF)."""
    z = logits.astype(np.float64) - logits.max(axis=1, keepdims=True)
    e = np.exp(z)
    return e / e.sum(axis=1, keepdims=True)


def _tensorboard(run_dir: Path) -> Any:
    """A TensorBoard writer under `run_dir/tb` when `tensorboard` is installed, else None."""
    try:
        import tensorboard  # noqa: F401
        from torch.utils.tensorboard import SummaryWriter
    except ImportError:
        return None
    return SummaryWriter(str(run_dir / "tb"))


def train(settings: TrainSettings, run_dir: str | Path, command: str = "",
          progress: Callable[[str], None] | None = None) -> TrainSummary:
    """Train (or resume) a run in `run_dir`; see `Trainer`."""
    return Trainer(settings, run_dir, command, progress).run()
