"""The app layer of sb3-twodrl: the commands, rl-zoo3's hook, export and the packaged settings.

What an SB3 user imports is :mod:`sb3_twodrl` (the algorithms, their policies, buffers, reward split and
callbacks); this package is the zoo around it, as rl-zoo3 is around SB3: ``sb3-twodrl-train`` and
``sb3-twodrl-enjoy`` (:mod:`twodrl_zoo.cli`), the registration in rl-zoo3 (:mod:`twodrl_zoo.zoo`), the packaged
hyperparameters and the one settings resolver (:mod:`twodrl_zoo.hyperparams`), and ``sb3-twodrl-export``
(:mod:`twodrl_zoo.export`).
"""
