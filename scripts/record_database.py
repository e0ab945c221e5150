"""Same as the installed ``sb3-twodrl-record-database`` (:mod:`twodrl_envs.analysis.cli`)."""

from twodrl_envs.analysis.cli import main

main()
