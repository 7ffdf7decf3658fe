"""Cases the fuzz campaign (``benchmarks/fuzz_campaign.py --only exact_blow``) found, each reduced to
its call: the exact blow under a feed and without a ``t_max``."""

import math

import pytest

import impactbar as ib
from impactbar.laws.rodrock import law as rl


def _blow(method="exact", t_max=None):
    # two incommensurate segments, a soft rock, a massless bit under a small feed: the piston's
    # return is not excluded for a long time while the waves break into ever more pieces
    rod = ib.RodRock(segments=[ib.RodSegment(2.956929223710221, 1.1545595384939695),
                               ib.RodSegment(5.338245678909666, 1.6270564485579473)],
                     rock=ib.BilinearRock(k=0.23451219667578274, k_u=0.677505588425157), bit_mass=0.0,
                     feed=0.020403656053167896)
    m = ib.BarModel(4.362857708746013, 0.0, 0.0, 0, impact=rod)
    return ib.single_blow(m, 0.2433127995020597, method=method, t_max=t_max)


def test_an_exact_blow_under_a_feed_without_t_max_ends_at_its_cost_bound(monkeypatch):
    """The blow ran to 2 million wave pieces (56 s; another of the campaign's to the pool's 2 GiB
    after 100 s); now ``EXACT_MAX_PIECES`` bounds it, and it ends as ``"budget"`` with the account
    closed and an ``uncertainty`` bounding what the rock could still take. The bound lowered here
    (the default, 1e5, costs some seconds) to keep the test short."""
    monkeypatch.setattr(rl, "EXACT_MAX_PIECES", 2_000)
    b = _blow()
    assert b.ended_by == "budget"
    assert b.energy_error < 1e-9
    assert math.isfinite(b.uncertainty) and b.uncertainty > 0.0
    assert 0.0 <= b.efficiency <= 1.0 and math.isfinite(b.times[-1])
    # a horizon before the bound ends there, with the same blow up to it
    bt = _blow(t_max=b.times[-1] * 0.5)
    assert bt.ended_by == "t_max" and bt.times[-1] == pytest.approx(b.times[-1] * 0.5)
    assert bt.work_on_rock <= b.work_on_rock * (1 + 1e-9)



def test_the_pools_refusal_of_a_blow_with_a_t_max_asks_for_a_shorter_one(monkeypatch):
    """Three incommensurate segments, a light bit, ``t_max = 19.5``: the waves broke into 1.85 million
    pieces and the pool's refusal asked to "give a t_max", which the call had given; now it names the
    time its pieces reached (the pool's bound lowered here to keep the test short)."""
    from impactbar.laws.rodrock import exact
    from impactbar.laws.rodrock.exact import PoolOverflow

    monkeypatch.setattr(exact, "MAX_POOL_BYTES", 2 ** 20)
    segs = [(0.7806521685020155, 0.7393413669078837), (3.1717029552752005, 1.5156220863708707),
            (13.809263981861763, 0.6437097575698593)]
    rod = ib.RodRock(segments=[ib.RodSegment(*g) for g in segs],
                     rock=ib.BilinearRock(k=2.708526063854057, k_u=68.66993173237992),
                     bit_mass=0.04994323955548905)
    m = ib.BarModel(7.254635737432778, 0.0, 0.0, 0, impact=rod)
    with pytest.raises(PoolOverflow, match=r"give a t_max below [0-9.]+, or use method='lattice'") as info:
        ib.single_blow(m, 0.706128330565426, method="exact", t_max=19.5315858826025)
    assert "\n" not in str(info.value)
    below = float(str(info.value).split("give a t_max below ")[1].split(",")[0])
    assert 0.0 < below < 19.5
