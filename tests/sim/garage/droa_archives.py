"""DeepRacer on AWS's model downloads, built from the real DeepRacer files in ../shared.

`virtual_model_archive` writes `virtualmodel-<name>.tar.gz` as DRoA's packaging Lambda
(`libs/lambda/src/async/assetpackaging.ts`) does: every object under the model's S3 folder
in the order S3 lists them, `sagemaker-artifacts/` taken out of each name, bare relative
paths, no directory entries, no sim-trace, videos or SageMaker output. The weights are the
real DeepRacer-trained graph of `car-model/sample-model.tar.gz`, as the simulator freezes
a checkpoint (`model/model_30.pb`, named best in `deepracer_checkpoints.json`); the metrics
are deepracer-for-cloud's real ones under DRoA's ISO-time names.
"""

from __future__ import annotations

import io
import json
import tarfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

TRAINING_ISO = "2026-07-24T15:06:12.345Z"
EVALUATION_ISO = "2026-07-24T16:20:05.001Z"
SUBMISSION_ISO = "2026-07-25T09:00:41.918Z"
JOB_ID = "Ta1b2c3d4e5f6g7"

DROA_PARAMS: dict[str, Any] = {
    "AWS_REGION": "us-east-1",
    "ROBOMAKER_SIMULATION_JOB_ACCOUNT_ID": "123456789012",
    "JOB_TYPE": "EVALUATION",
    "METRICS_S3_BUCKET": "droa-modelstorage-abc123",
    "KINESIS_VIDEO_STREAM_NAME": f"deepracerindy-evaluation-{JOB_ID}",
    "MODEL_NAME": "sample-model",
    "VIDEO_JOB_TYPE": "EVALUATION",
    "RACER_NAME": "speedy",
    "WORLD_NAME": "2022_april_open",
    "TRACK_DIRECTION_CLOCKWISE": True,
    "RACE_TYPE": "TIME_TRIAL",
    "BODY_SHELL_TYPE": "deepracer",
    "CAR_COLOR": "Orange",
    "NUMBER_OF_TRIALS": 3,
    "NUMBER_OF_RESETS": 10000,
    "IS_CONTINUOUS": True,
}


def _sample_car(shared: Path) -> tuple[dict[str, Any], bytes]:
    with tarfile.open(shared / "car-model" / "sample-model.tar.gz") as car:
        metadata_file = car.extractfile("model_metadata.json")
        graph_file = car.extractfile("agent/model.pb")
        assert metadata_file is not None and graph_file is not None
        metadata = json.loads(metadata_file.read())
        graph = graph_file.read()
    # DRoA writes version 6 as a number, and discrete actions without an index.
    metadata["version"] = 6
    if isinstance(metadata.get("action_space"), list):
        for action in metadata["action_space"]:
            action.pop("index", None)
    return metadata, graph


def virtual_model_members(
    shared: Path,
    *,
    params: Mapping[str, Any] | None = None,
    reward: str | None = None,
) -> dict[str, bytes]:
    """The archive's files by name, in DRoA's order."""
    metadata, graph = _sample_car(shared)
    drfc = shared / "drfc-model"
    evaluations = sorted((drfc / "metrics").glob("EvaluationMetrics-*.json"))
    training = f"deepracerindy-training-{JOB_ID}"
    evaluation = "deepracerindy-evaluation-Ea1b2c3d4e5f6g7"
    submission = "deepracerindy-submission-Sa1b2c3d4e5f6g7"
    meta_json = json.dumps(metadata, indent=2).encode()
    checkpoint = "30_Step-61000.ckpt"
    checkpoints = {
        "best_checkpoint": {"name": checkpoint, "time_stamp": 1721834772.5, "avg_eval_metric": 9.2},
        "last_checkpoint": {"name": checkpoint, "time_stamp": 1721834772.5, "avg_eval_metric": 9.2},
    }
    reward_source = (
        reward
        if reward is not None
        else (
            "def reward_function(params):\n"
            "    if params['all_wheels_on_track']:\n"
            "        return 1.0\n"
            "    return 1e-3\n"
        )
    )
    return {
        f"logs/training/{TRAINING_ISO}-{training}-simulation.log": b"simulation log\n",
        f"logs/training/{TRAINING_ISO}-{training}-training.log": b"training log\n",
        f"metrics/evaluation/{EVALUATION_ISO}-{evaluation}.json": evaluations[0].read_bytes(),
        f"metrics/submission/{SUBMISSION_ISO}-{submission}.json": evaluations[1].read_bytes(),
        f"metrics/training/{TRAINING_ISO}-{training}.json": (
            drfc / "metrics" / "TrainingMetrics.json"
        ).read_bytes(),
        "model_metadata.json": meta_json,
        "reward_function.py": reward_source.encode(),
        "evaluation_job_status.json": b'{"jobStatus": "CLOSED", "message": ""}',
        "ip/done": b"",
        "ip/hyperparameters.json": (drfc / "ip" / "hyperparameters.json").read_bytes(),
        "ip/ip.json": b'{"IP": "10.0.0.12"}',
        "model/.coach_checkpoint": f'model_checkpoint_path: "{checkpoint}"\n'.encode(),
        f"model/{checkpoint}.data-00000-of-00001": b"\0" * 64,
        f"model/{checkpoint}.index": b"\0" * 16,
        f"model/{checkpoint}.meta": b"\0" * 32,
        "model/deepracer_checkpoints.json": json.dumps(checkpoints).encode(),
        "model/model_30.pb": graph,
        "model/model_metadata.json": meta_json,
        "training_job_status.json": b'{"jobStatus": "CLOSED", "message": ""}',
        "training_params.yaml": yaml.safe_dump(
            {**DROA_PARAMS, **(params or {})}, sort_keys=False
        ).encode(),
    }


def write_archive(path: Path, members: Mapping[str, bytes]) -> Path:
    with tarfile.open(path, "w:gz") as tar:
        for name, data in members.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            info.mode = 0o644
            tar.addfile(info, io.BytesIO(data))
    return path


def virtual_model_archive(
    shared: Path,
    folder: Path,
    name: str = "sample-model",
    *,
    params: Mapping[str, Any] | None = None,
    drop: tuple[str, ...] = (),
    reward: str | None = None,
) -> Path:
    """`virtualmodel-<name>.tar.gz` in `folder`; `params` change training_params.yaml's
    keys (None as a value removes the key), `drop` leaves members out."""
    changed = dict(params or {})
    members = virtual_model_members(shared, params=changed, reward=reward)
    if any(value is None for value in changed.values()):
        kept = {k: v for k, v in {**DROA_PARAMS, **changed}.items() if v is not None}
        members["training_params.yaml"] = yaml.safe_dump(kept, sort_keys=False).encode()
    for name_dropped in drop:
        members.pop(name_dropped)
    folder.mkdir(parents=True, exist_ok=True)
    return write_archive(folder / f"virtualmodel-{name}.tar.gz", members)


def physical_model_archive(shared: Path, folder: Path, name: str = "sample-model") -> Path:
    """`physicalmodel-<name>.tar.gz`: the car archive SageMaker's output holds."""
    metadata, graph = _sample_car(shared)
    folder.mkdir(parents=True, exist_ok=True)
    return write_archive(
        folder / f"physicalmodel-{name}.tar.gz",
        {"model_metadata.json": json.dumps(metadata, indent=2).encode(), "agent/model.pb": graph},
    )
