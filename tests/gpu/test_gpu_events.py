"""The GPU step's events reach the world in the CPU step's order (gpu_shader.physics.cpu_events).

The shader records events in whatever order its invocations happen to run; `cpu_events` sorts
them by (step, stage, kind, body, other, slot) with `lexicographic_order`, one argsort of the
keys read as the digits of one int64. These tests hold that order to np.lexsort's on the same
keys, with no GPU: ties kept in their first order, rows that never tie (the faster sort's
case), negative keys, empty input, and keys too wide for 63 bits (then np.lexsort itself is
used).
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.physics import EVENT_KINDS, GPU_EVENT_DTYPE, cpu_events, lexicographic_order


def lexsort_order(keys):
    return np.lexsort(keys[::-1])


@pytest.mark.parametrize("seed", range(6))
def test_the_order_is_lexsorts_ties_and_negative_keys_included(seed):
    rng = np.random.default_rng(seed)
    count = int(rng.integers(1, 3000))
    # few distinct values per key, so that many rows tie on every key and stability shows
    keys = [rng.integers(low, low + int(rng.integers(1, 6)), count)
            for low in rng.integers(-5, 5, size=6)]
    np.testing.assert_array_equal(lexicographic_order(keys), lexsort_order(keys))


def test_rows_that_never_tie_come_out_in_the_same_order():
    """No two rows equal on every key (as no two events of a step are): the faster, unstable
    sort is kept, and it must give lexsort's order all the same."""
    rng = np.random.default_rng(5)
    unique = rng.permutation(6 * 7 * 8 * 9)[:2000]          # 2,000 distinct rows of 4 digits
    keys = [unique // (7 * 8 * 9) - 3, unique // (8 * 9) % 7, unique // 9 % 8, unique % 9]
    np.testing.assert_array_equal(lexicographic_order(keys), lexsort_order(keys))


def test_keys_too_wide_for_63_bits_fall_back_to_lexsort():
    rng = np.random.default_rng(1)
    keys = [rng.integers(-2 ** 40, 2 ** 40, 500) for _ in range(3)]   # 3 x 41 bits: too many
    keys[1][:250] = 7                                                 # ties on the middle key
    np.testing.assert_array_equal(lexicographic_order(keys), lexsort_order(keys))


def test_no_events_give_an_empty_log():
    assert len(cpu_events(np.zeros(0, GPU_EVENT_DTYPE), 1 / 240)) == 0


def test_events_come_out_by_step_stage_kind_body_other_and_slot():
    rng = np.random.default_rng(3)
    raw = np.zeros(4000, GPU_EVENT_DTYPE)
    raw["step"] = rng.integers(10, 14, len(raw))
    raw["stage"] = rng.choice([0, 1, 2, 9, 100, 101, 102, 200], len(raw))
    raw["kind"] = rng.integers(0, len(EVENT_KINDS), len(raw))
    raw["body"] = rng.integers(0, 50, len(raw))
    raw["other"] = rng.integers(-1, 50, len(raw))
    raw["slot"] = rng.integers(0, 4, len(raw))
    raw["speed"] = rng.random(len(raw))
    events = cpu_events(raw, 0.5)
    sweep = raw["stage"] < 100                    # only a sweep's events are ordered by kind
    kind = np.where(sweep, raw["kind"], 0)
    expected = raw[np.lexsort((raw["slot"], raw["other"], raw["body"], kind, raw["stage"],
                               raw["step"]))]
    np.testing.assert_array_equal(events["step"], expected["step"])
    np.testing.assert_array_equal(events["time"], expected["step"] * 0.5)
    np.testing.assert_array_equal(events["kind"], EVENT_KINDS[expected["kind"]])
    for name in ("body", "other", "speed", "impulse"):
        np.testing.assert_array_equal(events[name], expected[name])
