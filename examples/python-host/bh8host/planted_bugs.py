"""Two planted bugs for the example suite to catch (BH8HOST_BUG=lf or short-block picks one;
tests/conftest.py does the picking). Each is a one-line slip a real host library makes."""

from . import Hand


class LfHand(Hand):
    """Ends command lines in CR LF, as a terminal does: the hand takes the LF as the start of
    the next line (clause host-line-ending)."""

    LINE_END = b"\r\n"


class TrustingHand(Hand):
    """Parses whatever a feedback read returned: a block cut short by the hand is indexed as
    if it were whole."""

    def _read_block(self, size):
        return self._read_exactly(size)


BUGS = {"lf": LfHand, "short-block": TrustingHand}
