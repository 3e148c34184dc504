"""The compiled helpers of the per-step kernels equal numpy's reductions bit for bit, and the
kernels built on them equal the numpy formulas they replaced."""

from __future__ import annotations

import numpy as np
import pytest

from softhand.compiled import count_above, pairwise_sum, row_sums, within


@pytest.mark.parametrize("n", [*range(0, 40), 127, 128, 129, 255, 256, 300, 1000, 4097])
def test_pairwise_sum_is_numpys_sum_bit_for_bit(n):
    rng = np.random.default_rng(n)
    for _ in range(50):
        # magnitudes over 10 decades: the order of the additions shows in the last bits
        a = rng.standard_normal(n) * 10.0 ** rng.uniform(-5, 5, n)
        assert pairwise_sum(a) == a.sum()
        strided = rng.standard_normal((n, 4))[:, 1]  # a contact sensor's slots: every 4th entry
        assert pairwise_sum(strided) == strided.sum()


def test_a_sequential_sum_differs_so_the_order_is_tested():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((2000, 18)) * 10.0 ** rng.uniform(-5, 5, (2000, 18))
    sequential = np.array([sum(row.tolist()) for row in a])
    assert (sequential != a.sum(axis=1)).any()
    np.testing.assert_array_equal(row_sums(a), a.sum(axis=1))


def test_within_and_count_above():
    a = np.array([-1.0, 0.0, 0.5, 1.0])
    assert within(a, -1.0, 1.0)
    assert not within(a, -0.999, 1.0)
    assert not within(np.array([0.0, np.nan]), -1.0, 1.0)
    assert within(np.zeros(0), 0.0, 1.0)
    assert count_above(np.array([0.0, 1e-300, -2.0, 3.0, np.nan]), 0.0) == 2


def test_the_reward_kernel_is_the_documented_formula():
    from softhand.envs.partner import GRIP_PHALANGES, PHASES
    from softhand.envs.scenarios.handshake import CONTACT_N, handshake_reward

    rng = np.random.default_rng(4)
    worlds = 64
    f = rng.uniform(0, 14, (worlds, 18)) * (rng.uniform(size=(worlds, 18)) > 0.4)
    action = rng.uniform(-1, 1, (worlds, 6))
    phase = rng.integers(0, len(PHASES), worlds)
    grip = rng.uniform(5, 40, worlds)
    weights = rng.uniform(0, 2, (worlds, 4))
    overload = rng.uniform(3, 12, worlds)
    got = handshake_reward(f, action, phase, grip, weights, overload)
    # the module docstring's reward, in numpy
    engaged = np.isin(phase, [PHASES.index(p) for p in ("grip", "shake", "hold")])
    touched = f > CONTACT_N
    count = touched.sum(axis=1)
    mean = np.where(touched, f, 0.0).sum(axis=1) / np.maximum(count, 1)
    target = grip / GRIP_PHALANGES
    over = np.maximum(f - overload[:, None], 0.0)
    want = np.stack([np.where(engaged, -weights[:, 0] * ((mean - target) / target) ** 2, 0.0),
                     np.where(engaged, weights[:, 1] * count / 18, 0.0),
                     -weights[:, 2] * (over * over).sum(axis=1),
                     -weights[:, 3] * (action * action).sum(axis=1)], axis=1)
    assert engaged.any() and not engaged.all() and (over > 0).any()
    np.testing.assert_array_equal(got, want)


def test_interp_is_numpys_interp_bit_for_bit():
    """The compiled np.interp of one number, on increasing tables, tables with repeated knots
    (a running maximum, as the sensors' inverse tables), uniform ones, at the knots, between
    them, outside and at NaN."""
    from softhand.compiled import interp

    rng = np.random.default_rng(0)
    checked = 0
    for trial in range(120):
        m = int(rng.integers(2, 200))
        xp = np.sort(rng.uniform(0, 5, m))
        if trial % 3 == 0:
            xp = np.maximum.accumulate(np.round(xp, 1))  # repeated knots
        if trial % 5 == 0:
            xp = np.linspace(0.0, rng.uniform(1, 3), m)
        fp = np.cumsum(rng.uniform(0, 1, m)) ** rng.uniform(0.5, 2)
        for x in np.concatenate([rng.uniform(-0.5, 5.5, 100), xp, xp + 1e-15, [np.nan]]):
            want, got = np.interp(x, xp, fp), interp(float(x), xp, fp)
            assert got == want or (np.isnan(got) and np.isnan(want)), (x, got, want)
            checked += 1
    assert checked > 20_000
