"""A training fleet spread across processes steps, logs and fails as one fleet would."""

from __future__ import annotations

import json
import signal
from typing import Any

import numpy as np
import psutil
import pytest
import torch
from stable_baselines3.common.distributions import make_proba_distribution

from sim.garage.folder import ModelFolder
from sim.garage.options import new_model
from sim.reward.errors import RewardFunctionError
from sim.training import events
from sim.training.actor import ActorSetup, PolicyActor, training_mode
from sim.training.config import training_env_config
from sim.training.errors import describe_failure
from sim.training.fleet_parts import FleetPart, PartError, split_fleet
from sim.training.launcher import TrainingProcess
from sim.training.logbook import Logbook
from sim.training.policy import PolicyNetwork, init_weights, network_spec, observation_tensors
from sim.training.ppo_loss import evaluate_actions
from sim.training.shards import ShardedVecEnv
from sim.training.trainer import RunOptions, Trainer
from sim.training.vec_env import BatchedVecEnv, FleetVecEnv

CARS = 6
STEPS = 300


def test_a_fleet_is_split_as_evenly_as_it_comes() -> None:
    assert split_fleet(6, 3) == [FleetPart(0, 2), FleetPart(2, 2), FleetPart(4, 2)]
    assert split_fleet(7, 3) == [FleetPart(0, 3), FleetPart(3, 2), FleetPart(5, 2)]
    assert split_fleet(2, 4) == [FleetPart(0, 1), FleetPart(1, 1)]  # never an empty part
    with pytest.raises(ValueError):
        split_fleet(0, 2)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    return np.array_equal(a, b)


def _logbook(folder: ModelFolder, env: FleetVecEnv) -> Logbook:
    return Logbook(
        folder.path,
        cars=CARS,
        episodes_per_iteration=5,
        track_length=env.config.track.length,
        waypoints=env.config.track.center,
        discrete=env.config.action_space.kind == "discrete",
    )


@pytest.mark.parametrize("sensor", ["vector", "camera"])
def test_a_fleet_split_over_three_processes_steps_and_logs_as_the_whole_fleet(
    sensor: str,
) -> None:
    whole_model = new_model("whole", sensors=[sensor])
    split_model = new_model("split", sensors=[sensor])
    config = training_env_config(whole_model)
    whole = BatchedVecEnv(config, CARS)
    whole_log = _logbook(whole_model, whole)
    whole.batch.watcher = whole_log
    split_log = _logbook(split_model, whole)
    split = ShardedVecEnv(
        training_env_config(split_model), split_model.path, CARS, 3, on_step=split_log.add_step
    )
    try:
        assert split.processes == 3 and len(split.pids) == 2
        assert _same(whole.reset(), split.reset())
        rng = np.random.default_rng(7)
        ended = 0
        for step in range(STEPS):
            actions = rng.integers(0, len(config.action_space.actions), CARS)
            whole.step_async(actions)
            split.step_async(actions)
            obs_a, rewards_a, dones_a, infos_a = whole.step_wait()
            obs_b, rewards_b, dones_b, infos_b = split.step_wait()
            assert _same(obs_a, obs_b), f"step {step}"
            assert np.array_equal(rewards_a, rewards_b) and np.array_equal(dones_a, dones_b)
            assert whole.last_infos == split.last_infos
            for car in np.flatnonzero(dones_a).tolist():
                assert _same(
                    infos_a[car]["terminal_observation"], infos_b[car]["terminal_observation"]
                )
                assert infos_a[car]["TimeLimit.truncated"] == infos_b[car]["TimeLimit.truncated"]
            ended += int(dones_a.sum())
    finally:
        split.close()
    assert ended >= CARS  # random driving leaves the road: every part restarted its cars
    # Cars of every part finished episodes, and the one log numbered them as the whole's.
    cars = {episode.car for episode in split_log.take_finished()}
    assert cars & {0, 1} and cars & {2, 3} and cars & {4, 5}
    whole_log.flush()
    split_log.flush()
    for name in ("TrainingMetrics.json", "training-simtrace/0-iteration.csv"):
        files = [list(m.path.rglob(name.split("/")[-1])) for m in (whole_model, split_model)]
        assert len(files[0]) == len(files[1]) == 1
        assert files[0][0].read_bytes() == files[1][0].read_bytes()


def test_a_camera_fleets_simulation_processes_act_for_their_cars_with_the_trainers_weights() -> (
    None
):
    model = new_model("acting", sensors=["camera"])
    config = training_env_config(model)
    spec = network_spec(model.metadata())
    split = ShardedVecEnv(config, model.path, 4, 2, acting=ActorSetup(spec, bf16=False))
    whole = BatchedVecEnv(config, 4)
    network = PolicyNetwork(spec)
    init_weights(network)
    actor = PolicyActor(network, make_proba_distribution(whole.action_space), bf16=False)
    try:
        whole.reset()
        split.reset()
        acting = split.act(actor)
        here = whole.act(actor)
        assert _same(acting.pooled, here.pooled)
        assert np.allclose(acting.values, here.values, atol=1e-5)
        with torch.no_grad():  # the other process's cars were set the trainer's weights
            network.value_head.bias += 0.5
        again = split.act(actor)
        assert np.allclose(again.values, acting.values + 0.5, atol=1e-5)
        with torch.no_grad(), training_mode(network, bf16=False):
            _, log_probs, _ = evaluate_actions(
                network,
                make_proba_distribution(whole.action_space),
                observation_tensors(again.pooled),
                torch.as_tensor(again.actions),
            )
        assert np.allclose(again.log_probs, log_probs.numpy(), atol=1e-5)
        for step in range(40):
            rewards, dones, following = split.step_and_act(again, actor)
            rewards_here, dones_here, here = whole.step_and_act(again, actor)
            assert np.array_equal(rewards, rewards_here) and np.array_equal(dones, dones_here)
            assert _same(following.pooled, here.pooled), f"step {step}"
            assert np.allclose(following.values, here.values, atol=1e-5)
            assert following.final_values.keys() == here.final_values.keys()
            again = following
    finally:
        split.close()


def test_a_simulation_process_that_fails_raises_its_own_error_in_the_trainer() -> None:
    model = new_model("broken")
    good_config = training_env_config(model)  # read before the file breaks
    model.reward_file.write_text(
        "def reward_function(params):\n    return params['no such key']\n", encoding="utf-8"
    )
    split = ShardedVecEnv(good_config, model.path, 4, 2)
    try:
        split.reset()
        with pytest.raises(RewardFunctionError, match="line 2") as raised:
            for _ in range(3):  # step 1 is DeepRacer's prepare step: no reward call
                split.step_async(np.zeros(4, dtype=np.int64))
                split.step_wait()
        assert "no such key" in str(raised.value)
    finally:
        split.close()


@pytest.mark.parametrize("sensor", ["vector", "camera"])
def test_a_training_on_two_processes_drives_both_and_ends_them(sensor: str) -> None:
    model = new_model(f"two-{sensor}", sensors=[sensor])
    stream: list[events.Event] = []
    simulators: list[psutil.Process] = []

    def emit(event: events.Event) -> None:
        if isinstance(event, events.Started):
            assert isinstance(trainer.env, ShardedVecEnv)
            simulators.extend(psutil.Process(pid) for pid in trainer.env.pids)
            # A simulation process loads torch (start-up and memory) only to act for its
            # cars: where the network reads a camera.
            mapped = [m.path for p in simulators for m in p.memory_maps()]
            assert mapped
            assert any("torch" in path for path in mapped) == (sensor == "camera")
        stream.append(event)

    def stop() -> bool:
        return sum(isinstance(e, events.Update) for e in stream) >= 2

    options = RunOptions(minutes=5, cars=2, processes=2, seed=0, min_samples=32, max_samples=64)
    trainer = Trainer(model, emit, stop, options)
    stream.append(trainer.run())
    started, ended = stream[0], stream[-1]
    assert isinstance(started, events.Started)
    assert (started.cars, started.processes) == (4, 2)
    assert isinstance(ended, events.Ended) and ended.kind == "stopped", ended
    updates = [e for e in stream if isinstance(e, events.Update)]
    assert updates[-1].total_steps % 4 == 0 and updates[-1].total_steps > 0
    systems = [e for e in stream if isinstance(e, events.System)]
    assert systems and systems[0].rss_mb > 0
    # The simulation process is gone, and the model's files are a consistent training.
    assert len(simulators) == 1
    _, alive = psutil.wait_procs(simulators, timeout=10)
    assert not alive
    metrics = json.loads(model.training_metrics_file.read_text())
    assert len(metrics["metrics"]) >= 1
    assert model.has_policy()


def test_killing_the_trainer_ends_its_simulation_processes(model: ModelFolder) -> None:
    process = TrainingProcess.start(
        str(model.path), 5, ["--processes", "3", "--cars", "2", "--seed", "0"]
    )
    trainer = psutil.Process(process.pid)
    for event in process.events():
        if isinstance(event, events.Started):
            assert event.processes == 3
            break
    simulators = trainer.children()
    assert len(simulators) >= 2
    trainer.send_signal(signal.SIGKILL)
    process.wait()
    gone, alive = psutil.wait_procs(simulators, timeout=15)
    assert not alive, [p.pid for p in alive]
    assert len(gone) == len(simulators)


def test_a_simulation_process_that_dies_is_one_sentence_in_the_trainer() -> None:
    model = new_model("killed")
    split = ShardedVecEnv(training_env_config(model), model.path, 4, 2)
    try:
        split.reset()
        psutil.Process(split.pids[0]).kill()
        with pytest.raises(PartError, match=r"ended unexpectedly .*start the training again"):
            split.step_async(np.zeros(4, dtype=np.int64))
            split.step_wait()
    finally:
        split.close()


def test_a_reward_call_stuck_in_a_simulation_process_is_the_racers_sentence() -> None:
    model = new_model("stuck")
    good_config = training_env_config(model)
    model.reward_file.write_text(
        "import time\n"
        "def reward_function(params):\n"
        "    while True:\n"
        "        try:\n"
        "            time.sleep(1)\n"
        "        except BaseException:\n"
        "            pass\n",
        encoding="utf-8",
    )
    split = ShardedVecEnv(good_config, model.path, 4, 2, reward_seconds=0.2)
    try:
        split.reset()
        with pytest.raises(RewardFunctionError, match=r"did not return within 0\.2 s") as raised:
            for _ in range(3):
                split.step_async(np.zeros(4, dtype=np.int64))
                split.step_wait()
        said = describe_failure(raised.value)
        assert "make it return faster" in said and "please report" not in said
    finally:
        split.close()


def test_a_simulation_process_ending_is_said_without_blaming_racer_tui() -> None:
    said = describe_failure(PartError("a simulation process of this training ended"))
    assert said == "a simulation process of this training ended"


def test_what_a_reward_function_prints_in_a_simulation_process_stays_out_of_stdout(
    capfd: pytest.CaptureFixture[str],
) -> None:
    model = new_model("chatty")
    good_config = training_env_config(model)
    model.reward_file.write_text(
        "def reward_function(params):\n    print('REWARD-CHATTER')\n    return 1.0\n",
        encoding="utf-8",
    )
    split = ShardedVecEnv(good_config, model.path, 4, 2)
    try:
        split.reset()
        for _ in range(5):
            split.step_async(np.zeros(4, dtype=np.int64))
            split.step_wait()
    finally:
        split.close()  # the process ends, its buffers flushed
    out, err = capfd.readouterr()
    assert "REWARD-CHATTER" in err  # the training's event stream is stdout: not there
    assert "REWARD-CHATTER" not in out
