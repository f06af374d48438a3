"""The contract every store keeps, run against the shared folder and against DynamoDB on a
real loopback server: create-only idempotent push, cursor pulls, conflicts, versions."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from league.sync.protocol import ContentConflict, RecordStore, VersionConflict
from league.sync.record import Quarantined, SyncRecord, make_record
from tests.league.sync.conftest import StoreFactory
from tests.league.sync.records import (
    BASE_MS,
    fixed_id,
    keys,
    profile,
    submission,
    submissions,
)


@dataclass
class Pulled:
    records: list[SyncRecord] = field(default_factory=list)
    quarantined: list[Quarantined] = field(default_factory=list)
    pages: int = 0
    cursor: str | None = None


def pull_all(store: RecordStore, cursor: str | None = None, limit: int = 500) -> Pulled:
    pulled = Pulled(cursor=cursor)
    while True:
        page = store.pull(pulled.cursor, limit=limit)
        pulled.records.extend(page.records)
        pulled.quarantined.extend(page.quarantined)
        pulled.pages += 1
        pulled.cursor = page.next_cursor
        if not page.more:
            return pulled


def test_push_then_pull_returns_every_record_with_its_content(
    open_racer_store: StoreFactory,
) -> None:
    records = submissions(20)
    report = open_racer_store().push(records)
    assert len(report.pushed) == 20
    assert report.skipped == () and report.conflicts == ()

    pulled = pull_all(open_racer_store())
    assert keys(pulled.records) == keys(records)
    by_id = {record.record_id: record for record in pulled.records}
    for record in records:
        assert by_id[record.record_id].body == record.body
        assert by_id[record.record_id].content_hash == record.content_hash
    assert pulled.quarantined == []


def test_pushing_twice_sends_nothing_new(open_racer_store: StoreFactory) -> None:
    alice = open_racer_store()
    records = submissions(15)
    alice.push(records)
    reader = open_racer_store()
    first = pull_all(reader)

    again = alice.push(records)

    assert again.pushed == ()
    assert len(again.skipped) == 15 and again.conflicts == ()
    assert pull_all(reader, first.cursor).records == []


def test_a_push_interrupted_halfway_completes_without_duplicates(
    open_racer_store: StoreFactory,
) -> None:
    records = submissions(40)
    store = open_racer_store()

    def interrupt(done: int, total: int) -> None:
        if done >= 10:
            raise KeyboardInterrupt  # Ctrl+C while the push runs

    with pytest.raises(KeyboardInterrupt):
        store.push(records, progress=interrupt)
    partial = pull_all(open_racer_store()).records
    assert 0 < len(partial) < 40
    assert len({record.record_id for record in partial}) == len(partial)

    report = open_racer_store().push(records)

    assert len(report.pushed) + len(report.skipped) == 40
    assert len(report.skipped) == len(partial) and report.conflicts == ()
    assert keys(pull_all(open_racer_store()).records) == keys(records)


def test_push_of_half_then_all_pushes_only_the_rest(open_racer_store: StoreFactory) -> None:
    records = submissions(30)
    open_racer_store().push(records[:15])
    report = open_racer_store().push(records)
    assert sorted(ref.record_id for ref in report.pushed) == sorted(
        record.record_id for record in records[15:]
    )
    assert len(report.skipped) == 15
    assert keys(pull_all(open_racer_store()).records) == keys(records)


def test_same_id_with_other_content_is_a_conflict_and_never_overwrites(
    open_racer_store: StoreFactory,
) -> None:
    original = submission(1)
    rival = submission(1, best_lap_s=1.0)
    assert rival.record_id == original.record_id
    open_racer_store().push([original])

    report = open_racer_store().push([rival, submission(2)])

    assert report.conflicts == (
        ContentConflict(
            "submission", original.record_id, rival.content_hash, original.content_hash
        ),
    )
    assert [ref.record_id for ref in report.pushed] == [submission(2).record_id]
    pulled = {record.record_id: record for record in pull_all(open_racer_store()).records}
    assert pulled[original.record_id].content_hash == original.content_hash


def test_a_record_pushed_late_with_an_old_id_is_still_pulled(
    open_racer_store: StoreFactory,
) -> None:
    reader = open_racer_store()
    open_racer_store().push(submissions(5, ms=BASE_MS + 86_400_000))
    first = pull_all(reader)
    assert len(first.records) == 5

    # A racer who was offline all week pushes a submission created before all of those.
    late = submission(99, ms=BASE_MS - 7 * 86_400_000)
    open_racer_store().push([late])

    second = pull_all(reader, first.cursor)
    assert [record.record_id for record in second.records] == [late.record_id]
    assert pull_all(reader, second.cursor).records == []


def test_pull_pages_through_more_records_than_one_page(open_racer_store: StoreFactory) -> None:
    records = submissions(130)
    open_racer_store().push(records)

    pulled = pull_all(open_racer_store(), limit=25)

    assert pulled.pages >= 6
    assert keys(pulled.records) == keys(records)  # each exactly once


def test_a_new_pull_after_paging_sees_only_new_records(open_racer_store: StoreFactory) -> None:
    reader = open_racer_store()
    open_racer_store().push(submissions(30))
    first = pull_all(reader, limit=7)
    extra = submissions(3, start=500)
    open_racer_store().push(extra)
    assert keys(pull_all(reader, first.cursor, limit=7).records) == keys(extra)


def test_records_pushed_during_a_paged_pull_are_not_lost(open_racer_store: StoreFactory) -> None:
    reader, writer = open_racer_store(), open_racer_store()
    first_batch, second_batch = submissions(30), submissions(5, start=300)
    writer.push(first_batch)
    page = reader.pull(None, limit=10)
    assert page.more
    writer.push(second_batch)  # arrives while the reader is half-way through

    rest = pull_all(reader, page.next_cursor, limit=10)
    after = pull_all(reader, rest.cursor, limit=10)

    pulled = [*page.records, *rest.records, *after.records]
    assert keys(pulled) == keys(first_batch + second_batch)  # each exactly once


def test_a_racer_name_with_markup_travels_as_plain_text(open_racer_store: StoreFactory) -> None:
    racer = make_record("racer", fixed_id(BASE_MS, 7), {"name": "[bold red]x[/] <b>&amp;"})
    open_racer_store().push([racer])
    (pulled,) = pull_all(open_racer_store()).records
    assert pulled.body["name"] == "[bold red]x[/] <b>&amp;"


def test_a_profile_edit_from_a_stale_version_is_a_version_conflict(
    open_racer_store: StoreFactory,
) -> None:
    alice, bob = open_racer_store(), open_racer_store()
    assert alice.push([profile(1, 1, "Ada")]).pushed

    assert alice.push([profile(1, 2, "Ada Lovelace")]).pushed
    # Bob edited version 1 too, offline; his version 2 must not replace Alice's.
    stale = bob.push([profile(1, 2, "Countess")])
    assert stale.pushed == ()
    (conflict,) = stale.conflicts
    assert isinstance(conflict, VersionConflict)
    assert (conflict.local_version, conflict.remote_version) == (2, 2)
    assert conflict.remote_hash == profile(1, 2, "Ada Lovelace").content_hash

    # Re-pushing the exact stored version is not a conflict; an older one is.
    assert alice.push([profile(1, 2, "Ada Lovelace")]).skipped
    older = bob.push([profile(1, 1, "Countess")]).conflicts
    assert isinstance(older[0], VersionConflict) and older[0].remote_version in (1, 2)

    newest: dict[str, SyncRecord] = {}
    for record in pull_all(open_racer_store()).records:
        held = newest.get(record.record_id)
        if held is None or record.version > held.version:
            newest[record.record_id] = record
    assert newest[profile(1, 1, "x").record_id].body == {"display_name": "Ada Lovelace"}


def test_a_profile_update_is_pulled_again_by_a_reader_that_had_the_old_version(
    open_racer_store: StoreFactory,
) -> None:
    reader = open_racer_store()
    open_racer_store().push([profile(3, 1, "Grace")])
    first = pull_all(reader)
    assert [record.version for record in first.records] == [1]

    open_racer_store().push([profile(3, 2, "Grace Hopper")])

    second = pull_all(reader, first.cursor)
    assert [(record.version, record.body["display_name"]) for record in second.records] == [
        (2, "Grace Hopper")
    ]


def test_init_twice_is_harmless(open_racer_store: StoreFactory) -> None:
    store = open_racer_store()
    store.push(submissions(2))
    store.init()
    assert len(pull_all(open_racer_store()).records) == 2


def test_repeats_within_one_push_are_sent_once(open_racer_store: StoreFactory) -> None:
    record = submission(5)
    report = open_racer_store().push([record, record])
    assert len(report.pushed) == 1 and len(report.skipped) == 1
