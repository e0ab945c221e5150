"""Same as the installed ``sb3-twodrl-record-database`` (:mod:`envs.memorable.cli`)."""

from envs.memorable.cli import main

main()
