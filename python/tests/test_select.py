"""mmbm.choose_frames: the chosen indices from arrays, as `mmbm frames` chooses."""

import math

import numpy as np
import pytest

import mmbm


def blurs(n):
    # Distinct blurs 1..10 px, no two within 0.05 px.
    return np.array([1.0 + ((k * 37 + 11) % 91) * 0.1 for k in range(n)])


def test_per_window_picks_each_window_s_minimum():
    b = blurs(60)
    got = mmbm.choose_frames(b, per_window=10)
    want = [int(np.argmin(b[i : i + 10])) + i for i in range(0, 60, 10)]
    assert got.tolist() == want
    assert got.dtype == np.int64


def test_per_seconds_uses_the_times():
    b = blurs(20)
    t = np.arange(20) / 10  # windows of 0.5 s: frames 0-4, 5-9, ... (0.5, 1.0, 1.5 exact)
    got = mmbm.choose_frames(b, t, per_seconds=0.5)
    want = [int(np.argmin(b[i : i + 5])) + i for i in range(0, 20, 5)]
    assert got.tolist() == want
    with pytest.raises(ValueError, match="times_s"):
        mmbm.choose_frames(b, per_seconds=0.5)


def test_count_bounds_the_largest_hole():
    b = blurs(103)
    for n in (1, 7, 10, 50):
        got = mmbm.choose_frames(b, count=n).tolist()
        assert len(got) == n
        w = math.ceil(103 / n)
        assert all(y - x < 2 * w for x, y in zip(got, got[1:]))


def test_budget_and_select():
    b = blurs(40)
    b[3] = np.nan  # no value: never chosen
    assert mmbm.choose_frames(b, max_blur=4.52).tolist() == [k for k in range(40) if b[k] <= 4.52]
    got = mmbm.choose_frames(b, select=3)
    order = [k for k in np.argsort(b, kind="stable") if not np.isnan(b[k])][:3]
    assert got.tolist() == sorted(int(k) for k in order)


def test_bad_requests_are_value_errors():
    b = blurs(10)
    for kw in (
        {},
        {"per_window": 0},
        {"count": 0},
        {"per_window": 2, "count": 3},
        {"count": 3, "gap": 0.5},
        {"count": -1},
        {"max_blur": -1.0},
        {"per_window": 1.5},
    ):
        with pytest.raises(ValueError):
            mmbm.choose_frames(b, **kw)
    with pytest.raises(ValueError, match="times_s"):
        mmbm.choose_frames(b, np.arange(3.0), count=2)
