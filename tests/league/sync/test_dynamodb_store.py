"""DynamoDB specifics, on moto's real HTTP server: the table design, what a push sends,
hostile items, clock skew between racers, and a store that is down or not set up."""

from __future__ import annotations

import socket
from typing import Any

import boto3
import pytest

from league.sync.aws import ServerClock
from league.sync.dynamodb_store import DynamoDbStore
from league.sync.dynamodb_table import record_item, shard_of
from league.sync.errors import (
    StoreIncompatibleError,
    StoreNotInitialisedError,
    StoreUnavailable,
)
from league.sync.record import MAX_BODY_BYTES, make_record
from league.sync.urls import DynamoDbUrl
from tests.league.sync.conftest import QUICK_RETRY, MotoServer
from tests.league.sync.records import BASE_MS, fixed_id, keys, submission, submissions
from tests.league.sync.test_store_contract import pull_all


def _store(url: DynamoDbUrl, *, init: bool = True) -> DynamoDbStore:
    store = DynamoDbStore(url, retry=QUICK_RETRY)
    if init:
        store.init()
    return store


def _raw_client(url: DynamoDbUrl) -> Any:
    return boto3.client("dynamodb", region_name=url.region, endpoint_url=url.endpoint)


def test_init_creates_the_documented_table_design(dynamodb_url: DynamoDbUrl) -> None:
    _store(dynamodb_url).init()  # twice: idempotent
    table = _raw_client(dynamodb_url).describe_table(TableName=dynamodb_url.table)["Table"]
    assert table["TableStatus"] == "ACTIVE"
    assert table["KeySchema"] == [{"AttributeName": "pk", "KeyType": "HASH"}]
    (index,) = table["GlobalSecondaryIndexes"]
    assert index["IndexName"] == "by_push"
    assert [key["AttributeName"] for key in index["KeySchema"]] == ["shard", "pushed_key"]
    assert index["Projection"]["ProjectionType"] == "ALL"


def test_a_second_push_writes_nothing(dynamodb_url: DynamoDbUrl) -> None:
    store = _store(dynamodb_url)
    writes: list[str] = []
    store._client.meta.events.register(  # count the requests boto3 really sends
        "before-call.dynamodb.*", lambda event_name, **_: writes.append(event_name.split(".")[-1])
    )
    records = submissions(25)
    store.push(records)
    assert writes.count("PutItem") == 25
    writes.clear()

    report = store.push(records)

    assert len(report.skipped) == 25
    assert "PutItem" not in writes and "BatchWriteItem" not in writes
    assert writes == ["BatchGetItem"]


def test_a_record_at_the_size_limit_fits_in_one_item(dynamodb_url: DynamoDbUrl) -> None:
    body = {"notes": ["x" * 30_000] * 8, "more": "y" * (MAX_BODY_BYTES - 240_200)}
    record = make_record("race", fixed_id(BASE_MS, 1), body)
    store = _store(dynamodb_url)
    assert store.push([record]).pushed
    (pulled,) = pull_all(store).records
    assert pulled.content_hash == record.content_hash


def test_malformed_items_are_quarantined_and_the_rest_is_pulled(dynamodb_url: DynamoDbUrl) -> None:
    store = _store(dynamodb_url)
    good = submissions(4)
    store.push(good)
    client = _raw_client(dynamodb_url)

    def plant(**changes: Any) -> None:
        item = record_item(submission(90 + len(planted)), BASE_MS)
        item.update(changes)
        item["shard"] = {"S": shard_of(item["pk"]["S"])}
        client.put_item(TableName=dynamodb_url.table, Item=item)
        planted.append(item)

    planted: list[dict[str, Any]] = []
    plant(body={"S": "{not json"})
    plant(content_hash={"S": "0" * 64})
    plant(pk={"S": "script#01J00000000000000000000000"})
    plant(version={"S": "one"})
    plant(body={"S": '{"name": "\\u001b[2Jgotcha"}'})

    pulled = pull_all(_store(dynamodb_url, init=False))

    assert keys(pulled.records) == keys(good)
    assert len(pulled.quarantined) == 5
    assert all("\x1b" not in item.excerpt for item in pulled.quarantined)


def test_a_racer_with_a_slow_clock_is_not_missed_or_pulled_twice(
    dynamodb_url: DynamoDbUrl, monkeypatch: pytest.MonkeyPatch
) -> None:
    reader = _store(dynamodb_url)
    _store(dynamodb_url, init=False).push(submissions(3))
    first = pull_all(reader)
    assert len(first.records) == 3

    # This laptop's pushes are stamped two minutes in the past: behind the reader's cursor.
    slow = _store(dynamodb_url, init=False)
    clock = slow._call.clock
    now = clock.now_ms
    monkeypatch.setattr(clock, "now_ms", lambda: now() - 120_000)
    late = submission(50)
    slow.push([late])

    second = pull_all(reader, first.cursor)
    assert [record.record_id for record in second.records] == [late.record_id]
    assert pull_all(reader, second.cursor).records == []


def test_the_server_clock_comes_from_the_date_header() -> None:
    clock = ServerClock()
    clock.observe({"ResponseMetadata": {"HTTPHeaders": {"date": "Mon, 01 Jan 2024 00:00:00 GMT"}}})
    assert abs(clock.now_ms() - 1_704_067_200_000) < 60_000
    clock.observe({"ResponseMetadata": {"HTTPHeaders": {}}})  # no header: keep the offset
    assert clock.now_ms() < 1_800_000_000_000


def _closed_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_an_unreachable_endpoint_is_one_clear_sentence() -> None:
    endpoint = f"http://127.0.0.1:{_closed_port()}"
    store = DynamoDbStore(DynamoDbUrl("league", "us-east-1", endpoint), retry=QUICK_RETRY)
    with pytest.raises(StoreUnavailable) as caught:
        store.push(submissions(2))
    message = str(caught.value)
    assert message.startswith("cannot reach the DynamoDB table league")
    assert endpoint in message and "\n" not in message


def test_a_server_that_stops_mid_session_gives_store_unavailable() -> None:
    server = MotoServer()
    url = DynamoDbUrl("league", "us-east-1", server.endpoint)
    store = _store(url)
    store.push(submissions(3))
    cursor = pull_all(store).cursor
    server.stop()

    with pytest.raises(StoreUnavailable, match="cannot reach"):
        store.push(submissions(2, start=10))
    with pytest.raises(StoreUnavailable, match="cannot reach"):
        store.pull(cursor)


def test_a_missing_table_says_to_run_init(dynamodb_url: DynamoDbUrl) -> None:
    with pytest.raises(StoreNotInitialisedError, match="sync init dynamodb://"):
        _store(dynamodb_url, init=False).pull()


def test_a_table_without_the_racer_tui_mark_says_to_run_init(dynamodb_url: DynamoDbUrl) -> None:
    store = _store(dynamodb_url)
    _raw_client(dynamodb_url).delete_item(
        TableName=dynamodb_url.table, Key={"pk": {"S": "meta#store"}}
    )
    with pytest.raises(StoreNotInitialisedError, match="not set up as a racer-tui store"):
        _store(dynamodb_url, init=False).push(submissions(1))
    store.init()  # repairs it
    assert _store(dynamodb_url, init=False).push(submissions(1)).pushed


def test_a_foreign_table_is_refused(dynamodb_url: DynamoDbUrl) -> None:
    client = _raw_client(dynamodb_url)
    client.create_table(
        TableName=dynamodb_url.table,
        AttributeDefinitions=[{"AttributeName": "id", "AttributeType": "S"}],
        KeySchema=[{"AttributeName": "id", "KeyType": "HASH"}],
        BillingMode="PAY_PER_REQUEST",
    )
    with pytest.raises(StoreIncompatibleError, match="choose another table name"):
        _store(dynamodb_url, init=False).push(submissions(1))
    with pytest.raises(StoreIncompatibleError, match="choose another table name"):
        _store(dynamodb_url)
