"""Reading a DeepRacer car archive: the `.tar.gz` a physical car loads.

It holds `model_metadata.json` at its root and one frozen TensorFlow graph,
`agent/model.pb` (the car's loader rejects an archive unless it finds exactly one model
file); racer-tui's own export holds nothing else. Archives come from anyone, so this reader:

- never extracts to disk and never executes anything: members are read into memory;
- caps the archive's size, each member's size and the bytes decompressed in all, so a
  small file cannot expand into gigabytes;
- refuses absolute paths, `..`, links and devices;
- follows the car's loader on what else may be inside: it searches the archive for model
  files (by extension, testing `ext in ".pb"`, so a file with no extension counts too) and
  refuses it unless it finds exactly one. Other plain files (deepracer-for-cloud's car
  upload tars a whole model folder) are skipped unread, as the car ignores them;
- reads the metadata with `sim.deepracer.files` (the one home of DeepRacer's formats) and
  the graph with `sim.car_archive.graph_def` (known ops only);
- checks the graph has the input and output names the car uses for the metadata's sensor.

`car_archive_bytes` writes the container (the export and the model folder import use it).
No torch here: running the graph is `sim.car_archive.graph_runner`'s job.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import posixpath
import tarfile
import zlib
from dataclasses import dataclass
from pathlib import Path

from sim.car_archive.errors import CarModelError
from sim.car_archive.file_names import CAR_ARCHIVE_SUFFIXES
from sim.car_archive.graph_def import FrozenGraph, read_graph
from sim.deepracer.files import (
    MAX_METADATA_BYTES,
    MODEL_METADATA,
    SENSOR_FILE_NAMES,
    DeepRacerFileError,
    ModelMetadata,
    parse_model_metadata,
)
from sim.foundation.untrusted_tar import CappedStream, Unsafe, UnsafeMemberError, member_name

GRAPH_MEMBER = "agent/model.pb"
MEMBERS = (MODEL_METADATA, GRAPH_MEMBER)
# DeepRacer's deepest camera network is about 30 MB of float32 weights; leave ample room.
MAX_GRAPH_BYTES = 256 * 1024 * 1024
MAX_ARCHIVE_BYTES = MAX_GRAPH_BYTES + MAX_METADATA_BYTES
# Headers and padding on top of the two members, for everything decompressed.
MAX_UNPACKED_BYTES = MAX_ARCHIVE_BYTES + 1024 * 1024
MAX_ENTRIES = 16

# The car's tensor names (simapp's `boto/s3/constants.py` and the car's model loader's):
# network_0 holds the sensors' inputs. PPO's agent scope is "main" and its policy head sits
# in network_1; SAC's agent scope is "policy" and its head sits in network_0.
OUTPUT_NODES = {
    "clipped_ppo": "main_level/agent/main/online/network_1/ppo_head_0/policy",
    "sac": "main_level/agent/policy/online/network_0/sac_policy_head_0/policy",
}
AGENT_SCOPES = {"clipped_ppo": "main", "sac": "policy"}
INPUT_NODE = "main_level/agent/{agent}/online/network_0/{sensor}/{sensor}"
CAMERA_SENSORS = ("FRONT_FACING_CAMERA", "STEREO_CAMERAS")


@dataclass(frozen=True)
class CarArchive:
    """A checked car archive: its metadata, its graph, and the names to feed and read."""

    path: Path
    metadata: ModelMetadata
    graph: FrozenGraph
    sensor: str  # DeepRacer's name, e.g. FRONT_FACING_CAMERA
    input_node: str
    output_node: str
    content_hash: str  # sha256 of the two members

    @property
    def name(self) -> str:
        """The archive's file name without `.tar.gz`: what races and results call it."""
        name = self.path.name
        for suffix in CAR_ARCHIVE_SUFFIXES:
            if name.endswith(suffix):
                return name[: -len(suffix)]
        return self.path.stem


def car_archive_bytes(metadata_json: bytes, graph: bytes) -> bytes:
    """The `.tar.gz`: the two files, plain, owned by nobody, dated 0, so one model always
    gives the same bytes."""
    buffer = io.BytesIO()
    with (
        gzip.GzipFile(fileobj=buffer, mode="wb", mtime=0) as zipped,
        tarfile.open(fileobj=zipped, mode="w", format=tarfile.USTAR_FORMAT) as tar,
    ):
        for name, data in ((MODEL_METADATA, metadata_json), (GRAPH_MEMBER, graph)):
            info = tarfile.TarInfo(name)
            info.size = len(data)
            info.mode = 0o644
            tar.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def read_car_archive(path: Path) -> CarArchive:
    """Read and check a car archive; every problem is one `CarModelError` naming the file."""
    where = path.name
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise CarModelError(f"{path}: the file does not exist.") from None
    except OSError as error:
        raise CarModelError(f"{path}: cannot read it ({error.strerror}).") from None
    if not path.is_file():
        raise CarModelError(f"{path}: not a file; give the car archive (.tar.gz).")
    if size > MAX_ARCHIVE_BYTES:
        raise CarModelError(
            f"{where}: the file is {size:,} bytes, more than the {MAX_ARCHIVE_BYTES:,} a car "
            "archive may have."
        )
    members = _members(path, where)
    for name in MEMBERS:
        if name not in members:
            raise CarModelError(
                f"{where}: there is no {name}; a car archive holds model_metadata.json and "
                f"{GRAPH_MEMBER}."
            )
    metadata = _metadata(members[MODEL_METADATA], f"{where}: {MODEL_METADATA}")
    graph = read_graph(members[GRAPH_MEMBER], f"{where}: {GRAPH_MEMBER}")
    sensor, input_node, output_node = _tensor_names(metadata, graph, where)
    digest = hashlib.sha256()
    for name in MEMBERS:
        digest.update(hashlib.sha256(members[name]).digest())
    return CarArchive(path, metadata, graph, sensor, input_node, output_node, digest.hexdigest())


def _members(path: Path, where: str) -> dict[str, bytes]:
    """The archive's two files by normalised name, read under every limit."""
    found: dict[str, bytes] = {}
    try:
        with path.open("rb") as raw, gzip.GzipFile(fileobj=raw) as unzipped:
            limited = CappedStream(unzipped, MAX_UNPACKED_BYTES, lambda: _unpacked_too_much(where))
            # Stream mode: tarfile reads forwards only, so nothing is seeked or cached.
            with tarfile.open(fileobj=limited, mode="r|") as tar:
                for count, member in enumerate(tar, start=1):
                    if count > MAX_ENTRIES:
                        raise CarModelError(
                            f"{where}: the archive has more than {MAX_ENTRIES} entries; a car "
                            "archive holds model_metadata.json, agent/model.pb and little else."
                        )
                    name = _checked_name(member, where)
                    if name is None:
                        continue  # a directory entry, or a file the car ignores
                    if name in found:
                        raise CarModelError(f"{where}: {name} appears twice in the archive.")
                    found[name] = _read_member(tar, member, name, where)
    except CarModelError:
        raise
    except (tarfile.TarError, EOFError, zlib.error, OSError):  # BadGzipFile is an OSError
        raise CarModelError(
            f"{where}: not a complete gzip-compressed tar archive (truncated or corrupt); "
            "give the car archive (.tar.gz) as downloaded."
        ) from None
    return found


def _checked_name(member: tarfile.TarInfo, where: str) -> str | None:
    """The member's name without a leading './', or None for an allowed directory entry."""
    try:
        name = member_name(member)
    except UnsafeMemberError as unsafe:
        if unsafe.why is Unsafe.OUTSIDE:
            raise CarModelError(
                f"{where}: the member {unsafe.name!r} points outside the archive; a car "
                "archive holds only model_metadata.json and agent/model.pb."
            ) from None
        raise CarModelError(
            f"{where}: the member {unsafe.name!r} is a link or special file; a car archive "
            "holds only plain files (model_metadata.json and agent/model.pb)."
        ) from None
    if name is None:
        return None
    raw = member.name
    if name in MEMBERS:
        return name
    if is_model_file(name):
        raise CarModelError(
            f"{where}: the archive holds another model file {raw!r} beside {GRAPH_MEMBER}; "
            "the car loads an archive only when it finds exactly one."
        )
    return None  # the car ignores it, and so does racer-tui: it is never read


def is_model_file(name: str) -> bool:
    """Whether the car's loader counts `name` as a model file (model_loader_node.py:
    `os.path.splitext(name)[1] not in (".pb")` tests a substring of ".pb", so a name with
    no extension counts as well)."""
    return posixpath.splitext(name)[1] in ".pb"


def _read_member(tar: tarfile.TarFile, member: tarfile.TarInfo, name: str, where: str) -> bytes:
    limit = MAX_METADATA_BYTES if name == MODEL_METADATA else MAX_GRAPH_BYTES
    if member.size > limit:
        raise CarModelError(
            f"{where}: {name} is {member.size:,} bytes, more than the {limit:,} allowed."
        )
    handle = tar.extractfile(member)
    if handle is None:  # only for non-files, which _checked_name has refused
        raise CarModelError(f"{where}: {name} cannot be read as a file.")
    data = handle.read(limit + 1)
    if len(data) != member.size:
        raise CarModelError(f"{where}: {name} is cut short (truncated archive).")
    return data


def _metadata(data: bytes, where: str) -> ModelMetadata:
    try:
        return parse_model_metadata(data.decode("utf-8"), where)
    except UnicodeDecodeError:
        raise CarModelError(f"{where}: not UTF-8 text; it must be JSON.") from None
    except DeepRacerFileError as error:
        raise CarModelError(str(error)) from None


def _tensor_names(metadata: ModelMetadata, graph: FrozenGraph, where: str) -> tuple[str, str, str]:
    """(DeepRacer camera name, camera input node, output node) the car would use.

    DeepRacer's models have exactly one camera; a lidar beside it (DeepRacer Evo) is a
    second input, which must be in the graph under its own name too."""
    if "camera" not in metadata.sensors:
        sensed = " and ".join(SENSOR_FILE_NAMES[name] for name in metadata.sensors)
        raise CarModelError(
            f"{where}: the model senses {sensed} without a camera; DeepRacer's cars run only "
            "models with a camera among their sensors."
        )
    agent = AGENT_SCOPES[metadata.training_algorithm]
    output_node = OUTPUT_NODES[metadata.training_algorithm]
    if output_node not in graph.nodes:
        raise CarModelError(
            f"{where}: the graph has no output named {output_node!r}; it is not a DeepRacer policy."
        )
    for sensor in metadata.sensors:
        if sensor == "camera":
            continue
        name = INPUT_NODE.format(agent=agent, sensor=SENSOR_FILE_NAMES[sensor])
        if name not in graph.nodes:
            raise CarModelError(
                f"{where}: the metadata names the sensor {SENSOR_FILE_NAMES[sensor]}, but the "
                f"graph has no input named {name!r}."
            )
    # The metadata says "camera" for both of DeepRacer's cameras: the graph says which.
    for sensor in CAMERA_SENSORS:
        input_node = INPUT_NODE.format(agent=agent, sensor=sensor)
        if input_node in graph.nodes:
            return sensor, input_node, output_node
    expected = INPUT_NODE.format(agent=agent, sensor=CAMERA_SENSORS[0])
    raise CarModelError(
        f"{where}: the graph has no camera input named {expected!r}; it is not a DeepRacer "
        "camera model."
    )


def _unpacked_too_much(where: str) -> None:
    raise CarModelError(
        f"{where}: the archive unpacks to more than {MAX_UNPACKED_BYTES:,} bytes; a car "
        "archive holds one model of at most that size."
    )
