"""Two-dimensional evaluation reinforcement learning (2D-RL) for Stable-Baselines3."""
