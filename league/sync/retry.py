"""Retries with exponential backoff and full jitter, for transient store failures.

Throttling, 5xx answers and dropped connections are retried; everything else fails at
once. Jitter spreads out racers who all hit "sync" at the same moment on league night.
botocore's own retries are switched off (see aws.py) so this is the one retry budget,
and tests can shrink it to keep a "store down" case quick.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

T = TypeVar("T")


@dataclass(frozen=True)
class RetryPolicy:
    """How hard to try before declaring the store unavailable."""

    max_attempts: int = 6
    base_delay_s: float = 0.1
    max_delay_s: float = 5.0
    connect_timeout_s: float = 5.0
    read_timeout_s: float = 30.0

    def delay(self, attempt: int, rng: random.Random | None = None) -> float:
        """Full-jitter backoff before retry number `attempt` (1-based)."""
        ceiling = min(self.max_delay_s, self.base_delay_s * (2 ** (attempt - 1)))
        return (rng or random).uniform(0, ceiling)


def call_with_retry(
    call: Callable[[], T],
    is_transient: Callable[[BaseException], bool],
    policy: RetryPolicy,
    sleep: Callable[[float], None] = time.sleep,
) -> T:
    """Run `call`, retrying transient failures; the last failure propagates unchanged."""
    attempt = 1
    while True:
        try:
            return call()
        except Exception as exc:
            if attempt >= policy.max_attempts or not is_transient(exc):
                raise
            sleep(policy.delay(attempt))
            attempt += 1
