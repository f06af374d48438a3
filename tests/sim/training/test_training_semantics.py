"""Training follows the DeepRacer settings of the model folder: start positions, driving
direction, and a reward module per car."""

from __future__ import annotations

from dataclasses import replace

import pytest

from sim.deepracer.files import DeepRacerFileError, parse_training_params, write_training_params
from sim.env import BatchedDeepRacer
from sim.garage.folder import ModelFolder
from sim.training import events
from sim.training.config import model_env_config
from sim.training.trainer import RunOptions, Trainer
from tests.sim.test_reward_per_car import STATEFUL

TINY = RunOptions(minutes=5, cars=4, seed=0, min_samples=32, max_samples=64, evaluation_seconds=0)


def _set_training_params(model: ModelFolder, **changes: object) -> None:
    params = replace(model.training_params(), **changes)  # type: ignore[arg-type]
    write_training_params(model.training_params_file, params)


def _train(model: ModelFolder, updates: int = 1) -> tuple[Trainer, list[events.Event]]:
    stream: list[events.Event] = []

    def stop() -> bool:
        return sum(isinstance(e, events.Update) for e in stream) >= updates

    trainer = Trainer(model, stream.append, stop, TINY)
    stream.append(trainer.run())
    return trainer, stream


def test_a_stateful_reward_function_trains_without_error(model: ModelFolder) -> None:
    model.reward_file.write_text(STATEFUL, encoding="utf-8")
    _, stream = _train(model)
    ended = stream[-1]
    assert isinstance(ended, events.Ended)
    assert ended.kind == "stopped", ended.message


def test_training_params_choose_start_positions_and_directions(model: ModelFolder) -> None:
    _set_training_params(
        model,
        change_start_position=False,
        alternate_driving_direction=True,
        reverse_direction=True,
    )
    config = model_env_config(model)
    assert config.is_reversed
    assert not config.rules.change_start and config.rules.alternate_direction
    env = BatchedDeepRacer(config, 2)
    env.reset()
    track = config.track
    car0, car1 = env.sim.all_params()
    # REVERSE_DIR turns the track round; alternation turns car 1 back for its first episode.
    assert (car0["is_reversed"], car1["is_reversed"]) == (True, False)
    assert car0["waypoints"] == track.waypoints[::-1]
    assert car1["waypoints"] == track.waypoints
    # Both start on the (same) start line: CHANGE_START_POSITION is off.
    assert car0["x"] != car1["x"]  # facing opposite ways, the look-ahead points differ
    assert env.sim.fleet.x[0] == pytest.approx(env.sim.fleet.x[1])
    assert env.sim.fleet.y[0] == pytest.approx(env.sim.fleet.y[1])


def test_a_reversed_model_trains_and_evaluates_the_other_way_round(model: ModelFolder) -> None:
    _set_training_params(model, reverse_direction=True)
    trainer, stream = _train(model)
    assert isinstance(stream[-1], events.Ended) and stream[-1].kind == "stopped"
    track = model.track()
    sim = trainer.model.batched_env.batch.sim
    assert all(params["is_reversed"] for params in sim.all_params())
    assert (trainer.evaluation_track.points == track.points[::-1]).all()


@pytest.mark.parametrize(
    ("text", "expected"),
    [("'true'", True), ("'False'", False), ("true", True), ("no_such", None)],
)
def test_flags_read_as_deepracer_writes_them(text: str, expected: bool | None) -> None:
    yaml_text = f"WORLD_NAME: hairpin-circuit\nREVERSE_DIR: {text}\n"
    if expected is None:
        with pytest.raises(DeepRacerFileError, match="REVERSE_DIR must be true or false"):
            parse_training_params(yaml_text, "training_params.yaml")
        return
    params = parse_training_params(yaml_text, "training_params.yaml")
    assert params.reverse_direction is expected
    assert params.change_start_position is True  # simapp's default
    assert "REVERSE_DIR" in params.to_yaml()
