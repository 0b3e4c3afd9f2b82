import os

import pytest

import bh8host
from bh8host.planted_bugs import BUGS


@pytest.fixture
def Hand():
    """The library's Hand, or a planted bug's (BH8HOST_BUG=lf | short-block)."""
    bug = os.environ.get("BH8HOST_BUG")
    return BUGS[bug] if bug else bh8host.Hand
