"""Training: PPO for the paper's seven baselines (models, rollout storage, GAE, loss, trainer, submission)."""
