"""Machinery shared by the 2D-RL algorithms: buffers, policies, reward split, rollout collection, checks."""
