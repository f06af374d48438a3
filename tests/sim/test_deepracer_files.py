"""DeepRacer's file formats: our files round-trip, real DeepRacer files read, bad ones are named."""

from __future__ import annotations

import csv
import io
import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sim.deepracer.action_space import discrete_grid
from sim.deepracer.files import (
    HYPERPARAMETER_SPECS,
    SIM_TRACE_COLUMNS,
    DeepRacerFileError,
    EvaluationTrial,
    ModelMetadata,
    SimTraceColumns,
    SimTraceRow,
    SimTraceSample,
    TrainingEpisode,
    TrainingMetrics,
    TrainingParams,
    append_sim_trace,
    append_training_metrics,
    check_hyperparameters,
    default_hyperparameters,
    evaluation_metrics_path,
    evaluation_stamp,
    evaluation_trace_path,
    last_sim_trace_row,
    locate_files,
    parse_evaluation_metrics,
    parse_hyperparameters,
    parse_model_metadata,
    parse_training_params,
    read_evaluation_metrics,
    read_hyperparameters,
    read_model_metadata,
    read_sim_trace,
    read_training_metrics,
    read_training_params,
    sim_trace_lines,
    sim_trace_text,
    stamp_in,
    trace_status,
    training_metrics_end,
    training_trace_path,
    write_evaluation_metrics,
    write_hyperparameters,
    write_model_metadata,
    write_sim_trace,
    write_training_metrics,
    write_training_params,
)
from sim.deepracer.vocabulary import EpisodeStatus

# --- round trips ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "metadata",
    [
        ModelMetadata(discrete_grid(30, 5, 3, 2), ("vector",)),
        ModelMetadata(
            discrete_grid(20, 3, 4, 3), ("camera", "lidar"), "DEEP_CONVOLUTIONAL_NETWORK"
        ),
        ModelMetadata(
            discrete_grid().__class__(kind="continuous", steering_range=(-20, 25)),
            ("sector_lidar",),
        ),
    ],
)
def test_model_metadata_round_trips(tmp_path: Path, metadata: ModelMetadata) -> None:
    path = tmp_path / "model_metadata.json"
    write_model_metadata(path, metadata)
    assert read_model_metadata(path) == metadata
    data = json.loads(path.read_text())
    assert data["action_space_type"] == metadata.action_space.kind
    assert data["version"] == "5"


def test_deepracer_sensor_names_are_written(tmp_path: Path) -> None:
    path = tmp_path / "model_metadata.json"
    write_model_metadata(path, ModelMetadata(discrete_grid(), ("camera", "lidar")))
    assert json.loads(path.read_text())["sensor"] == ["FRONT_FACING_CAMERA", "LIDAR"]


def test_hyperparameters_round_trip_with_deepracer_defaults(tmp_path: Path) -> None:
    path = tmp_path / "hyperparameters.json"
    values = check_hyperparameters({"lr": 0.0001, "batch_size": 128.0})
    write_hyperparameters(path, values)
    read = read_hyperparameters(path)
    assert read == values
    assert read["batch_size"] == 128 and isinstance(read["batch_size"], int)
    defaults = default_hyperparameters()
    assert defaults["loss_type"] == "huber"
    assert defaults["discount_factor"] == 0.999
    assert defaults["num_episodes_between_training"] == 20


def test_training_params_round_trip_keeping_unknown_keys(tmp_path: Path) -> None:
    path = tmp_path / "training_params.yaml"
    params = TrainingParams("hairpin-circuit", max_minutes=15.0, track_hash="abc", extra={"X": 1})
    write_training_params(path, params)
    assert read_training_params(path) == params
    assert "WORLD_NAME: hairpin-circuit" in path.read_text()


def test_training_and_evaluation_metrics_round_trip(tmp_path: Path) -> None:
    episode = TrainingEpisode(12.5, 3000, 1000, 2000, 1, 1, "training", 37.0, "Off track")
    metrics = TrainingMetrics((episode,))
    write_training_metrics(tmp_path / "training.json", metrics)
    assert read_training_metrics(tmp_path / "training.json") == metrics
    trial = EvaluationTrial(100.0, 10000, 0, 9876, "Lap complete", trial=1)
    write_evaluation_metrics(tmp_path / "evaluation.json", [trial])
    assert read_evaluation_metrics(tmp_path / "evaluation.json") == (trial,)
    assert trial.lap_time_seconds == 9.876
    # Whole percentages are written whole, as DeepRacer does.
    assert '"completion_percentage": 100,' in (tmp_path / "evaluation.json").read_text()


def test_sim_trace_round_trips(tmp_path: Path) -> None:
    row = SimTraceRow(
        0, 1, 1.5, 2.5, 90.0, -15.0, 2.0, 3, 0.0, False, True, 0.5, 4, 17.5, 0.066, "prepare"
    )
    path = tmp_path / "sim-trace" / "0-iteration.csv"
    write_sim_trace(path, [row, row])
    assert read_sim_trace(path) == [row, row]
    assert trace_status(EpisodeStatus.LAP_COMPLETE) == "lap_complete"


def test_evaluations_are_named_as_drfc_names_them() -> None:
    from datetime import UTC, datetime

    early = evaluation_stamp(datetime(2025, 1, 2, 3, 4, 5, tzinfo=UTC))
    late = evaluation_stamp(datetime(2025, 11, 1, 0, 0, 0, tzinfo=UTC))
    assert early == "20250102030405"
    assert sorted([late, early]) == [early, late]
    assert evaluation_metrics_path(early) == "metrics/EvaluationMetrics-20250102030405.json"
    assert evaluation_trace_path(early) == (
        "evaluation-20250102030405/evaluation-simtrace/0-iteration.csv"
    )
    assert training_trace_path(0) == "training-simtrace/0-iteration.csv"
    assert stamp_in("evaluation-20250102030405-2.json") == early
    assert stamp_in("0-iteration.csv") is None


def _episode(n: int, phase: str = "training") -> TrainingEpisode:
    return TrainingEpisode(n + 0.5, 1000 * n, 1000 * n - 400, 400, n, n, phase, 12.5, "Off track")


def test_training_metrics_grow_by_appending(tmp_path: Path) -> None:
    path = tmp_path / "metrics" / "TrainingMetrics.json"
    path.parent.mkdir()
    sample = SimTraceSample(3, 2, 40, "a rule")
    append_training_metrics(path, [_episode(1), _episode(2)], TrainingMetrics(()))
    append_training_metrics(path, [], TrainingMetrics(()))
    append_training_metrics(path, [_episode(3)], TrainingMetrics((), sim_trace=sample))
    whole = TrainingMetrics((_episode(1), _episode(2), _episode(3)), sim_trace=sample)
    assert read_training_metrics(path) == whole
    # One JSON object as DeepRacer writes it, one row per line.
    data = json.loads(path.read_text())
    assert data["version"] == 2.0 and data["best_model_metric"] == "progress"
    assert len(path.read_text().splitlines()) == 5
    assert training_metrics_end(path) == (_episode(3), sample)
    assert not list(tmp_path.rglob(".*.tmp"))


def test_a_metrics_file_from_elsewhere_is_appended_to_once_rewritten(
    deepracer_dir: Path, tmp_path: Path
) -> None:
    path = tmp_path / "TrainingMetrics.json"
    shutil.copyfile(deepracer_dir / "drfc-model" / "metrics" / "TrainingMetrics.json", path)
    last, sample = training_metrics_end(path)
    assert last is not None and last.episode == 541 and sample is None
    original = read_training_metrics(path).episodes
    append_training_metrics(path, [_episode(542)], TrainingMetrics(()))
    assert read_training_metrics(path).episodes == (*original, _episode(542))
    assert training_metrics_end(path)[0] == _episode(542)


def test_sim_trace_columns_write_rows_deepracer_reads() -> None:
    columns = SimTraceColumns(
        episode=np.array([4, 4]),
        steps=np.array([1, 2]),
        x=np.array([1.234567, 1.3]),
        y=np.array([0.5, 0.25]),
        yaw=np.array([-179.99, 10.0]),
        steer=np.array([-30.0, 15.0]),
        throttle=np.array([1.0, 4.0]),
        action=np.array([0, 7]),
        reward=np.array([0.0, 0.75]),
        done=np.array([False, True]),
        all_wheels_on_track=np.array([True, False]),
        progress=np.array([0.5, 1.25]),
        closest_waypoint=np.array([3, 4]),
        track_len=17.5,
        tstamp=np.array([0.0666667, 0.1333333]),
        episode_status=["prepare", "off_track"],
    )
    text = ",".join(SIM_TRACE_COLUMNS) + "\n" + sim_trace_lines(columns)
    assert text.splitlines()[1] == (
        "4,1.0,1.2346,0.5000,-179.9900,-30.0000,1.0000,0,0.0000,False,True,0.5000,3,17.5,"
        "0.067,prepare,0.000"
    )
    rows = list(csv.DictReader(io.StringIO(text)))
    assert rows[1]["done"] == "True" and rows[1]["all_wheels_on_track"] == "False"
    assert rows[1]["episode_status"] == "off_track" and rows[1]["tstamp"] == "0.133"


def test_sim_trace_rows_are_appended_under_one_header(tmp_path: Path) -> None:
    path = tmp_path / "training-simtrace" / "0-iteration.csv"
    row = SimTraceRow(0, 1, 0, 0, 0, 0, 1, 0, 0, False, True, 0, 0, 17, 0, "prepare")
    line = sim_trace_text([row]).split("\n", 1)[1]
    append_sim_trace(path, line)
    append_sim_trace(path, line.replace("prepare", "in_progress"))
    assert [r.episode_status for r in read_sim_trace(path)] == ["prepare", "in_progress"]
    last = last_sim_trace_row(path)
    assert last is not None and last.episode_status == "in_progress"


# --- the real DeepRacer files ----------------------------------------------------------------


def test_the_drfc_model_folder_reads(deepracer_dir: Path) -> None:
    files = locate_files(deepracer_dir / "drfc-model")
    assert files.model_metadata == deepracer_dir / "drfc-model" / "model" / "model_metadata.json"
    assert files.hyperparameters == deepracer_dir / "drfc-model" / "ip" / "hyperparameters.json"
    assert files.reward_function is None
    assert [p.name for p in files.evaluation_metrics] == [
        "EvaluationMetrics-20220709200242.json",
        "EvaluationMetrics-20220709200509.json",
        "EvaluationMetrics-20220709200711.json",
    ]
    metadata = read_model_metadata(files.model_metadata)
    assert metadata.sensors == ("camera",)
    assert len(metadata.action_space.actions) == 14
    assert metadata.action_space.max_speed == 2.0
    hyperparameters = read_hyperparameters(files.hyperparameters)
    assert hyperparameters["discount_factor"] == 0.95
    assert hyperparameters["term_cond_max_episodes"] == 5000
    training = read_training_metrics(files.training_metrics[0])
    assert len(training.episodes) == 600
    assert {e.phase for e in training.episodes} == {"training", "evaluation"}
    trials = read_evaluation_metrics(files.evaluation_metrics[0])
    # DRfC runs continuous laps: every 100% trial is a lap, even those "In progress".
    assert [t.lap_time_seconds for t in trials] == [14.792, 13.801, 14.731]


def test_the_console_log_download_reads(deepracer_dir: Path) -> None:
    files = locate_files(deepracer_dir / "console-logs")
    assert files.model_metadata is None
    assert len(files.training_metrics) == 1
    assert files.latest_evaluation is not None
    trials = read_evaluation_metrics(files.latest_evaluation)
    assert [t.lap_time_seconds for t in trials] == [16.468, 16.267, 16.402]
    rows = read_sim_trace(files.sim_traces[0])
    assert len(rows) == 737
    assert rows[0].episode_status == "prepare"
    assert rows[-1].episode_status == "lap_complete" and rows[-1].progress == 100.0
    assert rows[0].track_len == pytest.approx(17.709, abs=1e-3)


def test_real_files_survive_our_writers(deepracer_dir: Path, tmp_path: Path) -> None:
    source = deepracer_dir / "drfc-model" / "metrics" / "TrainingMetrics.json"
    write_training_metrics(tmp_path / "training.json", read_training_metrics(source))
    assert json.loads((tmp_path / "training.json").read_text()) == json.loads(source.read_text())
    trace = deepracer_dir / "console-logs" / "sim-trace" / "evaluation" / "0-iteration.csv"
    original = read_sim_trace(trace)
    write_sim_trace(tmp_path / "trace.csv", original)
    # Timestamps are written to the millisecond, like DeepRacer's own; the rest is exact.
    assert read_sim_trace(tmp_path / "trace.csv") == [
        replace(row, tstamp=round(row.tstamp, 3)) for row in original
    ]


# --- malformed files are rejected, naming the file ------------------------------------------


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "not valid JSON (line 1"),
        ("[]", "expected a JSON object"),
        ('{"sensor": ["LIDAR"]}', "there is no action_space"),
        ('{"action_space": [{"steering_angle": 45, "speed": 1}]}', "steering_angle is 45 degrees"),
        (
            '{"action_space": [{"steering_angle": 0, "speed": 1}], "sensor": ["RADAR"]}',
            "unknown sensor",
        ),
        (
            '{"action_space": [{"steering_angle": 0, "speed": 1}], "sensor": "LIDAR"}',
            "sensor must be a list",
        ),
        (
            '{"action_space": [{"steering_angle": 0, "speed": 1}], "neural_network": "HUGE"}',
            "unknown neural_network 'HUGE'",
        ),
        (
            '{"action_space": [{"steering_angle": 0, "speed": 1}], "training_algorithm": "dqn"}',
            "training_algorithm must be clipped_ppo or sac",
        ),
    ],
)
def test_bad_model_metadata_is_named(tmp_path: Path, text: str, message: str) -> None:
    path = _write(tmp_path, "model_metadata.json", text)
    with pytest.raises(DeepRacerFileError) as caught:
        read_model_metadata(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert message in str(caught.value)


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"batch_size": 16}, "batch_size must be a whole number from 32 to 512, not 16"),
        ({"batch_size": 64.5}, "batch_size must be a whole number"),
        ({"lr": "fast"}, "lr must be a number from 1e-08 to 0.001"),
        ({"beta_entropy": True}, "beta_entropy must be a number from 0 to 1"),
        ({"loss_type": "l2"}, "loss_type must be 'huber' or 'mean squared error'"),
        ({"num_episodes_between_training": 101}, "from 5 to 100"),
        ({"momentum": 0.9}, "unknown hyperparameter 'momentum'"),
    ],
)
def test_bad_hyperparameters_say_the_allowed_range(
    tmp_path: Path, values: dict[str, object], message: str
) -> None:
    path = _write(tmp_path, "hyperparameters.json", json.dumps(values))
    with pytest.raises(DeepRacerFileError) as caught:
        read_hyperparameters(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert message in str(caught.value)


def test_every_tunable_hyperparameter_has_a_range() -> None:
    for spec in HYPERPARAMETER_SPECS.values():
        assert spec.choices or (spec.low is not None and spec.high is not None)
        assert spec.check(spec.default, "defaults") == spec.default


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("WORLD_NAME: [unclosed", "not valid YAML"),
        ("- a list", "expected a mapping"),
        ("RACE_TYPE: TIME_TRIAL", "WORLD_NAME (the track) is missing"),
        ("WORLD_NAME: oval\nMAX_MINUTES: -1", "MAX_MINUTES must be a positive number"),
        ("WORLD_NAME: !!python/object/apply:os.system ['true']", "not valid YAML"),
    ],
)
def test_bad_training_params_are_named(tmp_path: Path, text: str, message: str) -> None:
    path = _write(tmp_path, "training_params.yaml", text)
    with pytest.raises(DeepRacerFileError) as caught:
        read_training_params(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert message in str(caught.value)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("{}", "expected a 'metrics' list"),
        ('{"metrics": [1]}', "metrics row 1 is not an object"),
        ('{"metrics": [{"completion_percentage": 100}]}', "metrics row 1 has no 'metric_time'"),
        (
            '{"metrics": [{"completion_percentage": "all", "metric_time": 1, "start_time": 0,'
            ' "elapsed_time_in_milliseconds": 1, "episode_status": "Lap complete"}]}',
            "completion_percentage must be a number",
        ),
        (
            '{"metrics": [{"completion_percentage": 100, "metric_time": 1.5, "start_time": 0,'
            ' "elapsed_time_in_milliseconds": 1, "episode_status": "Lap complete"}]}',
            "metric_time must be a whole number",
        ),
    ],
)
def test_bad_evaluation_metrics_are_named(tmp_path: Path, rows: str, message: str) -> None:
    path = _write(tmp_path, "evaluation-1.json", rows)
    with pytest.raises(DeepRacerFileError) as caught:
        read_evaluation_metrics(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert message in str(caught.value)


def test_bad_sim_traces_are_named(tmp_path: Path) -> None:
    header = _write(tmp_path, "a.csv", "x,y\n1,2\n")
    with pytest.raises(DeepRacerFileError, match="not a DeepRacer sim-trace CSV"):
        read_sim_trace(header)
    good = SimTraceRow(0, 1, 0, 0, 0, 0, 1, 0, 0, False, True, 0, 0, 17, 0, "prepare")
    write_sim_trace(tmp_path / "b.csv", [good])
    text = (tmp_path / "b.csv").read_text() + "0,2.0,nan,0,0,0,1,0,0,False,True,0,0,17,0,x\n"
    bad_row = _write(tmp_path, "b.csv", text)
    with pytest.raises(DeepRacerFileError, match="line 3 is not a valid sim-trace row"):
        read_sim_trace(bad_row)


def test_unreadable_files_are_named(tmp_path: Path) -> None:
    with pytest.raises(DeepRacerFileError, match="the file does not exist"):
        read_model_metadata(tmp_path / "nothing.json")
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(DeepRacerFileError, match="not a UTF-8 text file"):
        read_hyperparameters(binary)
    huge = tmp_path / "huge.json"
    huge.write_text(" " * 1_000_001)
    with pytest.raises(DeepRacerFileError, match="more than the 1,000,000 allowed"):
        read_model_metadata(huge)
    deep = _write(tmp_path, "deep.json", "[" * 100_000)
    with pytest.raises(DeepRacerFileError, match=r"deep\.json"):
        read_model_metadata(deep)


def test_parsers_take_text_and_name_its_source() -> None:
    where = "bundle.zip (hyperparameters.json)"
    with pytest.raises(DeepRacerFileError, match=r"^bundle\.zip \(hyperparameters\.json\): lr"):
        parse_hyperparameters('{"lr": 1}', where)
    metadata = parse_model_metadata('{"action_space": [{"steering_angle": 0, "speed": 1}]}', "m")
    assert metadata.sensors == ("camera",)  # DeepRacer's default sensor
    assert parse_training_params("WORLD_NAME: oval\n", "p").world_name == "oval"
    assert parse_evaluation_metrics('{"metrics": []}', "e") == ()


def test_a_continuous_action_trace_reads_with_its_action_pair(tmp_path: Path) -> None:
    """DeepRacer writes a continuous space's action as "[steering speed]" (and may add
    columns after simapp's own): such a trace reads, its action as -1 like racer-tui's."""
    header = ",".join(SIM_TRACE_COLUMNS) + ",obstacle_crash_counter,wall_clock\n"
    row = (
        "100,2.0,-1.53,-1.70,177.3,-25.0,1.86,[-25.0 1.863806813054166],0.01,False,True,"
        "1.39,2,16.59,214.776,in_progress,0.0,0,1773216295.49\n"
    )
    path = tmp_path / "0-iteration.csv"
    path.write_text(header + row, encoding="utf-8")

    (read,) = read_sim_trace(path)

    assert read.action == -1
    assert read.steer == -25.0
    path.write_text(header + row.replace("[-25.0 1.86", "[-25.0 x1.86"), encoding="utf-8")
    with pytest.raises(DeepRacerFileError, match="line 2"):
        read_sim_trace(path)
