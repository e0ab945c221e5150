"""Gymnasium environments of the 2D-RL paper's navigation task."""
