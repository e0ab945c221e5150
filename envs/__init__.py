"""Gymnasium environments of the 2D-RL paper's navigation task.

Importing this package registers:

* ``NomadOffice-v0``: the office of paper section 3 with ideal sensors and exact 10 cm moves;
* ``NomadOfficeReal-v0``: the same office with sensor noise, sonar drop-outs and motion slip;
* ``NomadOfficeMemorable-v0``: the same task replayed from a recorded sensor database (MEMORABLE).

``NomadOffice-v0`` and ``NomadOfficeMemorable-v0`` also have a ``vector_entry_point``, their
batched env (``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``): sub-env
``i`` behaves exactly like ``gym.make(id)``; the realistic model moves off the lattice and has none.

All are truncated after 200 steps: six times the shortest detour (33 moves), so no sensible
route is cut short, while 0.9**200 ~ 1e-9 makes the cut invisible to a gamma 0.9 learner.
"""

from gymnasium import register

MAX_EPISODE_STEPS = 200

register(
    id="NomadOffice-v0",
    entry_point="envs.nomad.office:NomadOfficeEnv",
    vector_entry_point="envs.nomad.batched:BatchedNomadOffice",
    max_episode_steps=MAX_EPISODE_STEPS,
)
register(
    id="NomadOfficeReal-v0",
    entry_point="envs.nomad.office:NomadOfficeEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
    kwargs={"sensor_noise": True, "step_sd_cm": 1.0, "slip_sd_cm": 1.0},
)
register(
    id="NomadOfficeMemorable-v0",
    entry_point="envs.memorable.env:NomadOfficeMemorableEnv",
    vector_entry_point="envs.memorable.env:BatchedNomadOfficeMemorable",
    max_episode_steps=MAX_EPISODE_STEPS,
)
