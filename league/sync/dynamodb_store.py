"""The DynamoDB store (`dynamodb://TABLE?region=R[&endpoint=URL]`); the table design is in
dynamodb_table.py and the README.

Push: one BatchGetItem per 100 records finds what the table already holds (so pushing
twice writes nothing), then each remaining record is a PutItem conditional on
attribute_not_exists(pk) -- or, for a new version of a racer_profile, on the stored
version being the one it was edited from. BatchWriteItem cannot carry a condition, so no
record write uses it: an unconditional write could silently replace another racer's
record that arrived between our check and our write. Puts run on a few threads (each
is one atomic item, so Ctrl+C leaves whole records only). A failed condition returns
the stored item, which tells "same content" (skipped) from "different" (conflict).

Pull: Query the by_push index shard by shard for pushed_key > cursor. pushed_at comes
from the server's clock (the Date header), and the cursor re-reads an overlap window
(`skew_allowance_s`) before the last sweep's start, remembering the keys it already
returned there: a put that was in flight, stamped a moment earlier than a later one, or
not yet visible in the eventually-consistent index when we looked, is still found, and
nothing is returned twice.

Spare copies (league.sync.restore): a record whose item was deleted or replaced by
someone with write access to the table is written again by its maker, under its own key
if that is free, else as `<kind>#<id>#spare<n>` (n = 1..8), create-only like every put.
A pull reads a spare as the record it is a copy of.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from functools import partial
from typing import Any, Final

import botocore.exceptions

from league.sync.aws import AwsCaller, dynamodb_client, error_code, resolve_region
from league.sync.cursor import pack_cursor, unpack_cursor
from league.sync.dynamodb_table import (
    INDEX_NAME,
    META_PK,
    PK,
    PUSHED_KEY,
    SHARD,
    SHARD_COUNT,
    Item,
    create_table_request,
    decode_item,
    held_hash_and_version,
    meta_item,
    meta_problem,
    record_item,
    record_pk,
    shard_of,
    table_design_problem,
    watermark_key,
)
from league.sync.errors import (
    CursorInvalidError,
    StoreIncompatibleError,
    StoreNotInitialisedError,
    StoreUnavailable,
)
from league.sync.protocol import (
    DEFAULT_PAGE_SIZE,
    SPARE_SLOTS,
    Conflict,
    ContentConflict,
    ProgressCallback,
    PullPage,
    PushReport,
    RecordRef,
    VersionConflict,
    unique_records,
)
from league.sync.record import VERSIONED_KINDS, Quarantined, SyncRecord
from league.sync.retry import RetryPolicy
from league.sync.urls import DynamoDbUrl

_CURSOR_TYPE: Final = "dynamodb"
_BATCH_GET_LIMIT: Final = 100  # DynamoDB's maximum keys per BatchGetItem
_QUERY_LIMIT: Final = 1000
_TABLE_WAIT_S: Final = 600.0
_CREATE_ONLY: Final = "attribute_not_exists(#pk)"
_VERSION_MATCHES: Final = "#v = :expected"
_SPARE_PK: Final = re.compile(r"(?P<key>[a-z_]{1,32}#[0-9A-HJKMNP-TV-Z]{26})#spare[1-8]")


class DynamoDbStore:
    """A store in one DynamoDB table. One push or pull at a time per object."""

    def __init__(
        self,
        url: DynamoDbUrl,
        *,
        retry: RetryPolicy | None = None,
        workers: int = 8,
        skew_allowance_s: float = 300.0,
    ) -> None:
        self.url = url
        self.table = url.table
        self.workers = max(1, workers)
        self.skew_allowance_ms = int(skew_allowance_s * 1000)
        region = resolve_region(url.region, url.endpoint, str(url))
        where = url.endpoint or f"region {region}"
        self._call = AwsCaller(
            f"the DynamoDB table {url.table} ({where})", str(url), retry or RetryPolicy()
        )
        self._client = dynamodb_client(region, url.endpoint, self._call.policy, self.workers + 2)
        self._ready = False

    @property
    def description(self) -> str:
        return self._call.description

    def __enter__(self) -> DynamoDbStore:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        self._client.close()

    # -- set-up -------------------------------------------------------------------------

    def init(self) -> None:
        """Create the table and its index if missing, wait until ACTIVE, mark it; idempotent."""
        client = self._client

        def create() -> None:
            # Already there (or being created) is fine: checked below.
            with contextlib.suppress(client.exceptions.ResourceInUseException):
                client.create_table(**create_table_request(self.table))

        self._call(create)
        description = self._wait_until_active()
        problem = table_design_problem(description)
        if problem is not None:
            raise StoreIncompatibleError(
                f"the table {self.table} exists but is not a racer-tui store ({problem}): "
                "choose another table name"
            )

        def mark() -> None:
            # Marked before is fine: _check_ready verifies the mark.
            with contextlib.suppress(client.exceptions.ConditionalCheckFailedException):
                client.put_item(
                    TableName=self.table,
                    Item=meta_item(),
                    ConditionExpression=_CREATE_ONLY,
                    ExpressionAttributeNames={"#pk": PK},
                )

        self._call(mark)
        self._ready = False
        self._check_ready()

    def _wait_until_active(self) -> Mapping[str, Any]:
        waited = 0.0
        attempt = 1
        while True:
            description = self._call(
                lambda: self._client.describe_table(TableName=self.table)["Table"]
            )
            indexes = description.get("GlobalSecondaryIndexes", [])
            if description.get("TableStatus") == "ACTIVE" and all(
                index.get("IndexStatus") == "ACTIVE" for index in indexes
            ):
                return description
            if waited > _TABLE_WAIT_S:
                raise StoreUnavailable(
                    f"{self.description} is still not active after {_TABLE_WAIT_S / 60:.0f} "
                    "minutes: check it in the AWS console, then run init again"
                )
            delay = min(5.0, 0.2 * 2**attempt)
            _sleep(delay)
            waited += delay
            attempt += 1

    def _check_ready(self) -> None:
        if self._ready:
            return

        def read_mark() -> Any:
            try:
                return self._client.get_item(
                    TableName=self.table, Key={PK: {"S": META_PK}}, ConsistentRead=True
                )
            except botocore.exceptions.ClientError as exc:
                if error_code(exc) == "ValidationException":
                    return None  # the table's key is not ours
                raise

        response = self._call(read_mark)
        if response is None:
            raise StoreIncompatibleError(
                f"the table {self.table} exists but is not a racer-tui store (its key is not "
                f"{PK}): choose another table name"
            )
        self._call.clock.observe(response)
        problem = meta_problem(response.get("Item"))
        if problem == "missing":
            raise StoreNotInitialisedError(
                f"the table {self.table} is not set up as a racer-tui store: run "
                f"`racer-tui sync init {self.url}` first"
            )
        if problem is not None:
            raise StoreIncompatibleError(
                f"the table {self.table} was set up by a newer racer-tui: update racer-tui "
                "to sync with it"
            )
        self._ready = True

    # -- push ---------------------------------------------------------------------------

    def push(
        self, records: Iterable[SyncRecord], progress: ProgressCallback | None = None
    ) -> PushReport:
        self._check_ready()
        unique, repeats, local_conflicts = unique_records(records)
        held = self._held(unique)
        pushed: list[RecordRef] = []
        skipped: list[RecordRef] = list(repeats)
        conflicts: list[Conflict] = list(local_conflicts)
        to_put: list[tuple[SyncRecord, int | None]] = []
        for record in unique:
            decision = _decide(record, held.get(record_pk(record.kind, record.record_id)))
            if isinstance(decision, RecordRef):
                skipped.append(decision)
            elif isinstance(decision, ContentConflict | VersionConflict):
                conflicts.append(decision)
            else:
                to_put.append((record, decision[1]))
        done = len(unique) - len(to_put)
        if progress is not None and unique:
            progress(done, len(unique))
        for outcome in self._put_all(to_put):
            if isinstance(outcome, ContentConflict | VersionConflict):
                conflicts.append(outcome)
            elif outcome[0] == "pushed":
                pushed.append(outcome[1])
            else:
                skipped.append(outcome[1])
            done += 1
            if progress is not None:
                progress(done, len(unique))
        return PushReport(tuple(pushed), tuple(skipped), tuple(conflicts))

    def _held(self, records: list[SyncRecord]) -> dict[str, tuple[str | None, int]]:
        """pk -> (content hash, version) of the records the table already holds."""
        held: dict[str, tuple[str | None, int]] = {}
        pks = [record_pk(record.kind, record.record_id) for record in records]
        for start in range(0, len(pks), _BATCH_GET_LIMIT):
            keys: list[Item] = [{PK: {"S": pk}} for pk in pks[start : start + _BATCH_GET_LIMIT]]
            for item in self._batch_get(keys):
                pk = item.get(PK, {}).get("S")
                if isinstance(pk, str):
                    held[pk] = held_hash_and_version(item)
        return held

    def _batch_get(self, keys: list[Item], *, whole: bool = False) -> list[Item]:
        """BatchGetItem (key, hash and version only, or `whole` items), re-requesting
        unprocessed keys (throttling) with backoff."""
        found: list[Item] = []
        attempt = 1
        while keys:
            wanted: dict[str, Any] = {"Keys": keys, "ConsistentRead": True}
            if not whole:
                wanted["ProjectionExpression"] = "#pk, content_hash, #v"
                wanted["ExpressionAttributeNames"] = {"#pk": PK, "#v": "version"}
            request: dict[str, Any] = {self.table: wanted}
            response: Any = self._call(partial(self._client.batch_get_item, RequestItems=request))
            found.extend(response.get("Responses", {}).get(self.table, []))
            keys = list(response.get("UnprocessedKeys", {}).get(self.table, {}).get("Keys", []))
            if keys:
                if attempt >= self._call.policy.max_attempts:
                    raise StoreUnavailable(
                        f"{self.description} is still throttling reads after "
                        f"{attempt} tries: wait a minute and sync again"
                    )
                _sleep(self._call.policy.delay(attempt))
                attempt += 1
        return found

    def _put_all(
        self, to_put: list[tuple[SyncRecord, int | None]]
    ) -> Iterable[tuple[str, RecordRef] | Conflict]:
        if len(to_put) <= 1 or self.workers == 1:
            yield from (self._put(record, expected) for record, expected in to_put)
            return
        pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="dynamodb-push")
        try:
            futures: list[Future[tuple[str, RecordRef] | Conflict]] = [
                pool.submit(self._put, record, expected) for record, expected in to_put
            ]
            for future in futures:
                yield future.result()
        finally:
            # Ctrl+C: queued puts are dropped, running ones finish; each item is whole.
            pool.shutdown(wait=True, cancel_futures=True)

    def _put(self, record: SyncRecord, expected: int | None) -> tuple[str, RecordRef] | Conflict:
        """One conditional put; `expected` is the stored version a profile replaces."""
        client = self._client
        names = {"#pk": PK}
        values: dict[str, Any] = {}
        condition = _CREATE_ONLY
        if expected is not None:
            condition, names, values = (
                _VERSION_MATCHES,
                {"#v": "version"},
                {":expected": {"N": str(expected)}},
            )

        def attempt() -> Item | None:
            item = record_item(record, self._call.clock.now_ms())
            try:
                arguments: dict[str, Any] = {
                    "TableName": self.table,
                    "Item": item,
                    "ConditionExpression": condition,
                    "ExpressionAttributeNames": names,
                    "ReturnValuesOnConditionCheckFailure": "ALL_OLD",
                }
                if values:
                    arguments["ExpressionAttributeValues"] = values
                client.put_item(**arguments)
                return None
            except botocore.exceptions.ClientError as exc:
                if error_code(exc) != "ConditionalCheckFailedException":
                    raise
                old = dict(exc.response).get("Item")
                return dict(old) if isinstance(old, dict) else {}

        old = self._call(attempt)
        if old is None:
            return ("pushed", RecordRef.of(record))
        if not old:  # older servers do not return the item: read it
            old = self._call(
                lambda: self._client.get_item(
                    TableName=self.table,
                    Key={PK: {"S": record_pk(record.kind, record.record_id)}},
                    ConsistentRead=True,
                ).get("Item", {})
            )
        decision = _decide(record, held_hash_and_version(old) if old else None)
        if isinstance(decision, RecordRef):
            return ("skipped", decision)
        if isinstance(decision, tuple):
            # The stored item changed between our check and our put (another racer's push).
            return _conflict(record, held_hash_and_version(old) if old else (None, 0))
        return decision

    # -- spare copies (league.sync.restore) ----------------------------------------------

    def held_copies(
        self, keys: Sequence[tuple[str, str]], *, spares: bool = False
    ) -> dict[tuple[str, str], list[SyncRecord]]:
        """The whole records the table holds under each (kind, id): its own item, and with
        `spares` its spare copies too; an item that is not a whole record of that kind
        and id is no copy of it (the pull quarantines it)."""
        self._check_ready()
        slots = range(SPARE_SLOTS + 1) if spares else range(1)
        pks = [
            _spare_pk(kind, record_id, slot)
            for kind, record_id in keys
            if kind not in VERSIONED_KINDS
            for slot in slots
        ]
        copies: dict[tuple[str, str], list[SyncRecord]] = {key: [] for key in keys}
        for start in range(0, len(pks), _BATCH_GET_LIMIT):
            batch: list[Item] = [{PK: {"S": pk}} for pk in pks[start : start + _BATCH_GET_LIMIT]]
            for item in self._batch_get(batch, whole=True):
                held = _decode(item)
                if isinstance(held, SyncRecord) and held.key in copies:
                    copies[held.key].append(held)
        return copies

    def write_spare(self, record: SyncRecord) -> str | None:
        """Write `record` again: as its own item if that key is free (it was deleted), else
        as the first free spare copy. The key it went to, or None when all are taken."""
        self._check_ready()
        if record.kind in VERSIONED_KINDS:
            return None
        client = self._client
        for slot in range(SPARE_SLOTS + 1):
            pk = _spare_pk(record.kind, record.record_id, slot)

            def put(pk: str = pk, slot: int = slot) -> bool:
                item = record_item(record, self._call.clock.now_ms())
                if slot:
                    item[PK] = {"S": pk}
                    item[SHARD] = {"S": shard_of(pk)}
                    # Its own place in the pull's index, apart from the item it copies.
                    item[PUSHED_KEY] = {"S": f"{item[PUSHED_KEY]['S']}#spare{slot}"}
                try:
                    client.put_item(
                        TableName=self.table,
                        Item=item,
                        ConditionExpression=_CREATE_ONLY,
                        ExpressionAttributeNames={"#pk": PK},
                    )
                except botocore.exceptions.ClientError as exc:
                    if error_code(exc) != "ConditionalCheckFailedException":
                        raise
                    return False
                return True

            if self._call(put):
                return pk
        return None

    # -- pull ---------------------------------------------------------------------------

    def pull(self, cursor: str | None = None, limit: int = DEFAULT_PAGE_SIZE) -> PullPage:
        self._check_ready()
        state = _Cursor.load(cursor)
        if state.sweep_start is None:
            state.start_sweep(self._call.clock.now_ms())
        assert state.sweep_start is not None
        keep_above = watermark_key(state.sweep_start - self.skew_allowance_ms)
        records: list[SyncRecord] = []
        quarantined: list[Quarantined] = []
        wanted = max(1, limit)

        def page_full() -> bool:
            return len(records) + len(quarantined) >= wanted

        for shard in (str(number) for number in range(SHARD_COUNT)):
            while shard not in state.done and not page_full():
                after = state.positions.get(shard, state.watermark)
                remaining = wanted - len(records) - len(quarantined)
                response = self._call(partial(self._query, shard, after, remaining))
                items = response.get("Items", [])
                used = 0
                for item in items:
                    used += 1
                    key = item[PUSHED_KEY]["S"]
                    state.positions[shard] = key
                    if key not in state.seen:
                        outcome = _decode(item)
                        if isinstance(outcome, SyncRecord):
                            records.append(outcome)
                        else:
                            quarantined.append(outcome)
                        if key > keep_above:  # inside the next overlap window: remember it
                            state.seen.add(key)
                    if page_full():
                        break
                if not items or (used == len(items) and "LastEvaluatedKey" not in response):
                    state.done.add(shard)
            if page_full():
                break
        more = len(state.done) < SHARD_COUNT
        if not more:
            state.finish_sweep(self.skew_allowance_ms)
        return PullPage(tuple(records), tuple(quarantined), state.pack(), more)

    def _query(self, shard: str, after: str, limit: int) -> Any:
        # Ask for no more than the page still needs: every item read costs read capacity.
        arguments: dict[str, Any] = {
            "TableName": self.table,
            "IndexName": INDEX_NAME,
            "Limit": max(1, min(limit, _QUERY_LIMIT)),
            "ExpressionAttributeNames": {"#s": SHARD},
            "ExpressionAttributeValues": {":s": {"S": shard}},
            "KeyConditionExpression": "#s = :s",
        }
        if after:
            arguments["KeyConditionExpression"] = "#s = :s AND #k > :after"
            arguments["ExpressionAttributeNames"]["#k"] = PUSHED_KEY
            arguments["ExpressionAttributeValues"][":after"] = {"S": after}
        return self._client.query(**arguments)


def _spare_pk(kind: str, record_id: str, slot: int) -> str:
    """The key of a record's item (slot 0) or of its spare copy `slot`."""
    pk = record_pk(kind, record_id)
    return f"{pk}#spare{slot}" if slot else pk


def _decode(item: Item) -> SyncRecord | Quarantined:
    """A pulled item as a record; a spare copy reads as the record it copies."""
    pk = item.get(PK, {}).get("S") if isinstance(item.get(PK), dict) else None
    spare = _SPARE_PK.fullmatch(pk) if isinstance(pk, str) else None
    if spare is not None and spare["key"].partition("#")[0] not in VERSIONED_KINDS:
        item = {**item, PK: {"S": spare["key"]}}
    return decode_item(item)


def _decide(
    record: SyncRecord, held: tuple[str | None, int] | None
) -> RecordRef | Conflict | tuple[str, int | None]:
    """What to do with `record` given what the table holds under its key.

    Returns a RecordRef (skip: already there), a conflict, or ("put", expected version).
    """
    if held is None:
        return ("put", None)
    stated, version = held
    if stated == record.content_hash and version == record.version:
        return RecordRef.of(record)
    if record.kind in VERSIONED_KINDS and version == record.version - 1:
        return ("put", version)
    return _conflict(record, held)


def _conflict(record: SyncRecord, held: tuple[str | None, int]) -> Conflict:
    stated, version = held
    if record.kind in VERSIONED_KINDS:
        return VersionConflict(
            record.kind, record.record_id, record.version, version, record.content_hash, stated
        )
    return ContentConflict(record.kind, record.record_id, record.content_hash, stated)


class _Cursor:
    """Pull position: everything pushed up to `watermark` was returned; keys above it that
    were returned are in `seen`; a sweep in progress has per-shard positions."""

    def __init__(self) -> None:
        self.watermark = ""
        self.seen: set[str] = set()
        self.sweep_start: int | None = None
        self.positions: dict[str, str] = {}
        self.done: set[str] = set()

    @classmethod
    def load(cls, cursor: str | None) -> _Cursor:
        state = cls()
        if cursor is None:
            return state
        data = unpack_cursor(_CURSOR_TYPE, cursor)
        try:
            state.watermark = _text(data["watermark"])
            state.seen = {_text(key) for key in data["seen"]}
            sweep = data["sweep"]
            if sweep is not None:
                state.sweep_start = int(sweep["start"])
                state.positions = {_text(k): _text(v) for k, v in dict(sweep["positions"]).items()}
                state.done = {_text(shard) for shard in sweep["done"]}
        except (KeyError, TypeError, ValueError):
            raise CursorInvalidError(
                "the saved sync position is damaged: pull from the start to rebuild it"
            ) from None
        return state

    def start_sweep(self, now_ms: int) -> None:
        self.sweep_start = now_ms
        self.positions = {}
        self.done = set()

    def finish_sweep(self, skew_allowance_ms: int) -> None:
        assert self.sweep_start is not None
        self.watermark = max(self.watermark, watermark_key(self.sweep_start - skew_allowance_ms))
        self.seen = {key for key in self.seen if key > self.watermark}
        self.sweep_start = None
        self.positions = {}
        self.done = set()

    def pack(self) -> str:
        sweep = (
            None
            if self.sweep_start is None
            else {
                "start": self.sweep_start,
                "positions": self.positions,
                "done": sorted(self.done),
            }
        )
        state = {"watermark": self.watermark, "seen": sorted(self.seen), "sweep": sweep}
        return pack_cursor(_CURSOR_TYPE, state)


def _text(value: object) -> str:
    if not isinstance(value, str):
        raise TypeError("not a string")
    return value


def _sleep(seconds: float) -> None:
    time.sleep(seconds)
