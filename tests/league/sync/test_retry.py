"""Retries with backoff: transient failures are retried within a budget, others are not."""

from __future__ import annotations

import random
from typing import Any

import botocore.exceptions
import pytest

from league.sync.aws import AwsCaller, is_transient
from league.sync.errors import StoreAccessDeniedError, StoreUnavailable
from league.sync.retry import RetryPolicy, call_with_retry


def _client_error(code: str, status: int = 400) -> botocore.exceptions.ClientError:
    response: Any = {
        "Error": {"Code": code, "Message": code},
        "ResponseMetadata": {"HTTPStatusCode": status},
    }
    return botocore.exceptions.ClientError(response, "PutItem")


def test_backoff_grows_exponentially_with_full_jitter_and_a_ceiling() -> None:
    policy = RetryPolicy(base_delay_s=0.1, max_delay_s=1.0)
    rng = random.Random(7)
    for attempt, ceiling in [(1, 0.1), (2, 0.2), (3, 0.4), (4, 0.8), (5, 1.0), (9, 1.0)]:
        delays = [policy.delay(attempt, rng) for _ in range(200)]
        assert all(0 <= delay <= ceiling for delay in delays)
        assert max(delays) > ceiling * 0.8  # jitter spreads over the whole range


def test_throttling_is_retried_until_it_passes() -> None:
    answers: list[Exception | str] = [
        _client_error("ProvisionedThroughputExceededException"),
        _client_error("InternalServerError", 500),
        "ok",
    ]
    slept: list[float] = []

    def call() -> str:
        answer = answers.pop(0)
        if isinstance(answer, Exception):
            raise answer
        return answer

    result = call_with_retry(call, is_transient, RetryPolicy(max_attempts=5), slept.append)
    assert result == "ok" and len(slept) == 2


def test_a_permanent_error_is_not_retried() -> None:
    calls = []

    def call() -> None:
        calls.append(1)
        raise _client_error("ValidationException")

    with pytest.raises(botocore.exceptions.ClientError):
        call_with_retry(call, is_transient, RetryPolicy(max_attempts=5), lambda _: None)
    assert len(calls) == 1


def test_the_budget_runs_out_into_one_clear_sentence() -> None:
    caller = AwsCaller(
        "the DynamoDB table t", "dynamodb://t", RetryPolicy(max_attempts=3, base_delay_s=0)
    )
    calls = []

    def throttled() -> None:
        calls.append(1)
        raise _client_error("ThrottlingException")

    with pytest.raises(StoreUnavailable, match=r"throttling .* after 3 tries"):
        caller(throttled)
    assert len(calls) == 3

    def refused() -> None:
        raise _client_error("UnrecognizedClientException")

    with pytest.raises(StoreAccessDeniedError, match="credentials"):
        caller(refused)
