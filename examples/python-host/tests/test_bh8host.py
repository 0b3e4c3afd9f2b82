"""bh8host's own tests, against graded simulated hands (the gcl pytest plugin)."""

import pytest

from bh8host import BH8Error


def test_version(gcl_hand, Hand):
    with Hand(gcl_hand.url) as hand:
        hand.sync()
        assert hand.version()


@pytest.mark.gcl(profile="bh8-262-4.3")
def test_home_then_positions(gcl_hand, Hand):
    with Hand(gcl_hand.url) as hand:
        hand.sync()
        hand.home()
        positions = hand.get("P", motors="123")
        assert len(positions) == 3


@pytest.mark.gcl(allow=["host-valid-commands"])
def test_a_refusal_is_an_error(gcl_hand, Hand):
    with Hand(gcl_hand.url) as hand:
        hand.sync()
        with pytest.raises(BH8Error, match="refused"):
            hand.command("FGET NOSUCHPARAM")


def test_realtime(gcl_hand, Hand):
    with Hand(gcl_hand.url) as hand:
        hand.sync()
        hand.home()
        cycles = hand.realtime_positions([20, 20, 20], cycles=4)
        assert len(cycles) == 4 and all(len(c) == 3 for c in cycles)


@pytest.mark.gcl(ops="rt-block-length,rt-err,truncate", schedules=4, seed=3, timeout=30)
def test_realtime_under_misbehaviour(gcl_misbehaving_hand, Hand):
    """A broken answer is a BH8Error, never a wrong position or a crash."""
    with Hand(gcl_misbehaving_hand.url, timeout=0.5) as hand:
        with gcl_misbehaving_hand.tolerate(BH8Error):
            hand.sync()
            hand.home()
            for cycle in hand.realtime_positions([20, 20, 20], cycles=4):
                assert len(cycle) == 3
