"""What the tests share: toy envs and a toy study, a cloned policy, the tabular oracle, the recording CPU's check,
and the collapse probe (``python -m tests.helpers.collapse_probe``)."""
