"""The exported TorchScript policy picks model.predict(..., deterministic=True)'s actions."""

import json
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from stable_baselines3 import A2C

import twodrl_envs  # noqa: F401
from sb3_twodrl import TwoDimA2C
from twodrl_zoo.export import export_onnx, export_policy, main


@pytest.mark.parametrize("algo", [TwoDimA2C, A2C])
def test_exported_actions_equal_deterministic_predict(tmp_path, algo):
    th.manual_seed(0)
    env = gym.make("twodrl_envs:NomadOfficeMemorable-v0")
    model = algo("MlpPolicy", env, n_steps=8, gamma=0.9, seed=0, device="cpu")
    model.learn(64)  # a few updates, so the weights are not the initial ones
    path = export_policy(model, tmp_path / "policy.pt")
    extra = {"meta.json": ""}
    loaded = th.jit.load(str(path), _extra_files=extra)
    assert json.loads(extra["meta.json"])["algorithm"] == algo.__name__
    batch = _observations(200, seed=1)
    expected, _ = model.predict(batch, deterministic=True)
    got = loaded(th.as_tensor(batch)).numpy()
    assert got.dtype == np.int64 and np.array_equal(got, expected)
    assert int(loaded(th.as_tensor(batch[:1]))[0]) == int(model.predict(batch[0], deterministic=True)[0])


def test_cli(tmp_path):
    model = TwoDimA2C("MlpPolicy", gym.make("twodrl_envs:NomadOfficeMemorable-v0"), seed=0, device="cpu")
    model.save(tmp_path / "m.zip")
    main([str(tmp_path / "m.zip"), str(tmp_path / "p.pt")])
    # the robot side needs torch only: load and run with stable_baselines3 and sb3_twodrl blocked
    code = (
        "import sys; sys.modules['stable_baselines3'] = None; sys.modules['sb3_twodrl'] = None; "
        f"import torch; p = torch.jit.load({str(tmp_path / 'p.pt')!r}); "
        "print(int(p(torch.zeros(1, 34))[0]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() in {"0", "1", "2", "3"}


def test_cli_loads_the_named_algorithm(tmp_path, capsys):
    model = A2C("MlpPolicy", gym.make("twodrl_envs:NomadOfficeMemorable-v0"), seed=0, device="cpu")
    model.save(tmp_path / "m.zip")
    with pytest.raises(ValueError, match="saved by another algorithm"):  # the default --algo is twoda2c
        main([str(tmp_path / "m.zip"), str(tmp_path / "p.pt")])
    main([str(tmp_path / "m.zip"), str(tmp_path / "p.pt"), "--algo", "a2c"])
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'p.pt'}"
    extra = {"meta.json": ""}
    th.jit.load(str(tmp_path / "p.pt"), _extra_files=extra)
    assert json.loads(extra["meta.json"])["algorithm"] == "A2C"


def _observations(n_random: int, seed: int = 2) -> np.ndarray:
    """61 readings of the stand-in robot under random moves (reset with ``seed``), then ``n_random`` random vectors."""
    rng = np.random.default_rng(0)
    real = gym.make("twodrl_envs:NomadOfficeReal-v0")
    obs = [real.reset(seed=seed)[0]]
    for _ in range(60):
        o, _, term, trunc, _ = real.step(int(rng.integers(4)))
        obs.append(real.reset()[0] if term or trunc else o)
    return np.concatenate([np.stack(obs), rng.random((n_random, 34), dtype=np.float32)])


@pytest.mark.parametrize("algo", [TwoDimA2C, A2C])
def test_onnx_actions_equal_deterministic_predict(tmp_path, algo):
    ort = pytest.importorskip("onnxruntime")
    pytest.importorskip("onnx")
    th.manual_seed(0)
    model = algo(
        "MlpPolicy", gym.make("twodrl_envs:NomadOfficeMemorable-v0"), n_steps=8, gamma=0.9, seed=0, device="cpu"
    )
    model.learn(64)
    path = export_onnx(model, tmp_path / "policy.onnx")
    session = ort.InferenceSession(str(path))
    assert json.loads(session.get_modelmeta().custom_metadata_map["meta.json"])["algorithm"] == algo.__name__
    batch = _observations(300)
    expected, _ = model.predict(batch, deterministic=True)
    got = session.run(["action"], {"obs": batch})[0]
    assert got.dtype == np.int64 and np.array_equal(got, expected)
    # one reading at a time, as on the robot
    stream = [int(session.run(["action"], {"obs": row[None]})[0][0]) for row in batch[:20]]
    assert stream == [int(model.predict(row, deterministic=True)[0]) for row in batch[:20]]


def test_onnx_cli_runs_without_torch_or_sb3(tmp_path):
    pytest.importorskip("onnxruntime")
    pytest.importorskip("onnx")
    TwoDimA2C("MlpPolicy", gym.make("twodrl_envs:NomadOfficeMemorable-v0"), seed=0, device="cpu").save(
        tmp_path / "m.zip"
    )
    main([str(tmp_path / "m.zip"), str(tmp_path / "p.onnx"), "--format", "onnx"])
    code = (
        "import sys; sys.modules['torch'] = None; sys.modules['stable_baselines3'] = None; "
        "import numpy, onnxruntime; "
        f"s = onnxruntime.InferenceSession({str(tmp_path / 'p.onnx')!r}); "
        "print(int(s.run(['action'], {'obs': numpy.zeros((1, 34), numpy.float32)})[0][0]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() in {"0", "1", "2", "3"}


class GridObservationEnv(gym.Env):
    """Observations of shape (3, 5), not the office's (34,); three actions."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (3, 5), np.float32)
    action_space = gym.spaces.Discrete(3)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action):
        return self.observation_space.sample(), float(action == 1), False, False, {}


@pytest.mark.parametrize("fmt", ["torchscript", "onnx"])
def test_any_box_observation_shape_exports(tmp_path, fmt):
    model = TwoDimA2C("MlpPolicy", GridObservationEnv(), n_steps=8, seed=0, device="cpu").learn(64)
    batch = np.random.default_rng(0).uniform(-1, 1, (50, 3, 5)).astype(np.float32)
    expected, _ = model.predict(batch, deterministic=True)
    if fmt == "onnx":
        ort = pytest.importorskip("onnxruntime")
        pytest.importorskip("onnx")
        session = ort.InferenceSession(str(export_onnx(model, tmp_path / "p.onnx")))
        meta = json.loads(session.get_modelmeta().custom_metadata_map["meta.json"])
        got = session.run(["action"], {"obs": batch})[0]
    else:
        extra = {"meta.json": ""}
        got = th.jit.load(str(export_policy(model, tmp_path / "p.pt")), _extra_files=extra)(th.as_tensor(batch))
        got, meta = got.numpy(), json.loads(extra["meta.json"])
    assert np.array_equal(got, expected) and len(set(expected.tolist())) > 1
    assert meta["observation_shape"] == [3, 5] and meta["n_actions"] == 3


def test_continuous_actions_are_refused(tmp_path):
    model = TwoDimA2C("MlpPolicy", "Pendulum-v1", seed=0, device="cpu")
    with pytest.raises(ValueError, match=r"Box observations and Discrete actions only.*action_space=Box"):
        export_policy(model, tmp_path / "p.pt")


@pytest.mark.parametrize("fmt", ["torchscript", "onnx"])
def test_the_exported_policy_takes_the_robots_raw_readings(tmp_path, fmt):
    """With the env's input stage (``--input-stage``), the exported graph takes ranges and odometry in cm and
    chooses ``model.predict``'s action on the env's observation of the same state, at every lattice cell."""
    from stable_baselines3.common.env_util import make_vec_env

    from sb3_twodrl import TwoDimA2C
    from twodrl_envs.nomad.core import office_core
    from twodrl_zoo.export import deploy_input, export_onnx, export_policy

    if fmt == "onnx":
        pytest.importorskip("onnxruntime")
    options = {"map": "generated:S:4"}
    model = TwoDimA2C("MlpPolicy", make_vec_env("NomadOffice-v0", n_envs=4, seed=0, env_kwargs=options), seed=0)
    generator = th.Generator().manual_seed(0)
    with th.no_grad():  # weights that prefer different actions in different cells
        for parameter in model.policy.parameters():
            parameter.copy_(th.randn(parameter.shape, generator=generator))
    core = office_core(options["map"])
    raw = np.concatenate([core.ranges, core.lattice.cells], axis=1)  # what the robot measures, cm
    expected, _ = model.predict(np.concatenate([core.readings, core.cell_odometry], axis=1), deterministic=True)
    stage = deploy_input("NomadOffice-v0", options)
    if fmt == "onnx":
        import onnxruntime

        path = export_onnx(model, tmp_path / "policy.onnx", input_stage=stage)
        actions = onnxruntime.InferenceSession(str(path)).run(["action"], {"obs": raw})[0]
    else:
        path = export_policy(model, tmp_path / "policy.pt", input_stage=stage)
        actions = th.jit.load(str(path))(th.as_tensor(raw)).numpy()
    assert len(set(expected.tolist())) > 1  # a policy that does not choose one action everywhere
    np.testing.assert_array_equal(actions, expected)
