"""Same as the installed ``sb3-twodrl-record-database`` (:mod:`twodrl_envs.memorable.cli`)."""

from twodrl_envs.memorable.cli import main

main()
