"""Record ids sort by creation time and are safe to use as names; hashes see content only."""

from __future__ import annotations

from sim.foundation.ids import content_hash, id_time_ms, is_valid_id, new_id


def test_ids_made_in_a_burst_are_unique_and_sorted_by_creation() -> None:
    ids = [new_id() for _ in range(2000)]
    assert len(set(ids)) == len(ids)
    assert ids == sorted(ids)


def test_an_id_carries_its_creation_time() -> None:
    record_id = new_id(now_ms=1_700_000_000_123)
    assert id_time_ms(record_id) == 1_700_000_000_123
    assert new_id(now_ms=1_800_000_000_000) > record_id


def test_only_well_formed_ids_are_valid() -> None:
    assert is_valid_id(new_id())
    for bad in (
        "",
        "../etc/passwd",
        "01ARZ3NDEKTSV4RRFFQ69G5FA",
        "01ARZ3NDEKTSV4RRFFQ69G5FAVX",
        "01ARZ3NDEKTSV4RRFFQ69G5FA/",
        "01arz3ndektsv4rrffq69g5fav",
        42,
        None,
    ):
        assert not is_valid_id(bad), bad


def test_content_hash_ignores_key_order_but_not_values() -> None:
    a = {"racer": "Ada", "laps": [12.5, 13.0], "valid": True}
    b = {"valid": True, "laps": [12.5, 13.0], "racer": "Ada"}
    assert content_hash(a) == content_hash(b)
    assert content_hash(a) != content_hash({**a, "racer": "Ada "})
    assert len(content_hash(a)) == 64
