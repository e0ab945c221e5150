"""Analysis of the office task, apart from the env classes: the dilemma measured exactly on the lattice
(:mod:`.dilemma`), the simulator-to-robot gap (:mod:`.gap`), recording a sensor database
(:mod:`twodrl_envs.memorable.recording`) and its command ``sb3-twodrl-record-database`` (:mod:`.cli`)."""
