"""MEMORABLE: training from a database of recorded sensor readings (paper section 3.1)."""
