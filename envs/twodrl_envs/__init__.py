"""Gymnasium environments of the 2D-RL paper's navigation task.

Importing this package registers:

* ``NomadOffice-v0``: the office of paper section 3 with ideal sensors and exact 10 cm moves;
* ``NomadOfficeReal-v0``: the same office on a stand-in for the physical robot (``twodrl_envs.nomad.realistic``:
  specular sonar, ringing, cross-talk, surface-dependent infrared, drifting odometry);
* ``NomadOfficeMemorable-v0``: the same task replayed from a recorded sensor database (MEMORABLE);
* ``NomadOfficeMuJoCo-v0``: the same office on a physics stand-in (``twodrl_envs.nomad.physics``: the robot's
  mass, acceleration and contacts in MuJoCo, sensors as ray casts; needs ``pip install "sb3-twodrl[mujoco]"``);
  registered without a ``vector_entry_point`` (one physics robot per env: ``gym.make_vec`` and SB3 step copies
  of it);
* ``NomadOfficeOpen-v0`` / ``NomadOfficeRealOpen-v0`` / ``NomadOfficeMemorableOpen-v0``: the three on the open
  office (start, gap and goal in one line: no dilemma; ``map="open"``, which any of the IDs also
  takes), kept so results can be shown on both maps.

Every ID takes ``map=``: a built-in map (``"office"``, ``"open"``, ``"corridor"``: one route, no route
regions), a map file (docs/own_office.md) or a generated office (``"generated:SIZE:SEED"``,
``twodrl_envs.nomad.generator``). Every ID but ``NomadOfficeMuJoCo-v0`` has a ``vector_entry_point``, its batched env
(``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point", **options)``), which takes every
option of ``gym.make(id, **options)``: sub-env ``i`` behaves exactly like ``gym.make(id, **options)`` (tested).

and, for the benchmark (``twodrl_envs.public``, docs/public_tasks.md), public tasks whose punishment is
written into ``info["punishment"]`` (``reward_split="info"``):

* ``LunarLanderSplit-v3``: LunarLander-v3, crash and fuel as punishment;
* ``CliffWalkingSplit-v1``: CliffWalking-v1 with a 100-step limit, the cliff as punishment;
* ``LavaGapSplit-v0``: MiniGrid-LavaGapS7-v0 with lava punished (needs ``minigrid``).

The Nomad IDs are all truncated after 300 steps: the shortest the wall-avoiding random walks of property P5
(docs/nomad.md) need to reach the default office's goal by the detour in at least a quarter of their
successes (280), rounded up; 0.9**300 ~ 2e-14 makes the cut invisible to a gamma 0.9 learner.
"""

from gymnasium import register

MAX_EPISODE_STEPS = 300

NOMAD_ENVS = {
    "NomadOffice": ("twodrl_envs.nomad.office:NomadOfficeEnv", "twodrl_envs.nomad.batched:BatchedNomadOffice"),
    "NomadOfficeReal": (
        "twodrl_envs.nomad.realistic:NomadOfficeRealEnv",
        "twodrl_envs.nomad.realistic:BatchedNomadOfficeReal",
    ),
    "NomadOfficeMemorable": (
        "twodrl_envs.memorable.env:NomadOfficeMemorableEnv",
        "twodrl_envs.memorable.env:BatchedNomadOfficeMemorable",
    ),
}
"""Name: (entry point, vector entry point) of each Nomad env; each is registered on the office and the open map."""

for name, (entry_point, vector_entry_point) in NOMAD_ENVS.items():
    for suffix, kwargs in (("", {}), ("Open", {"map": "open"})):
        register(
            id=f"{name}{suffix}-v0",
            entry_point=entry_point,
            vector_entry_point=vector_entry_point,
            max_episode_steps=MAX_EPISODE_STEPS,
            kwargs=dict(kwargs),
        )

register(
    id="NomadOfficeMuJoCo-v0",
    entry_point="twodrl_envs.nomad.physics:NomadOfficeMuJoCoEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
)

for env_id, maker in (
    ("LunarLanderSplit-v3", "make_lunar_lander"),
    ("CliffWalkingSplit-v1", "make_cliff_walking"),
    ("LavaGapSplit-v0", "make_lava_gap"),
):
    register(id=env_id, entry_point=f"twodrl_envs.public:{maker}")
