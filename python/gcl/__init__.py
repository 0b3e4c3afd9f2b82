"""gcl: the Grasper Control Language conformance kit, from Python.

The wheel puts the ``gcl`` binary on PATH (``gcl --help``), ships the stdlib-only
``gcl_vectors`` runner, and this package, which starts and stops simulated hands:

    from gcl import Hand

    with Hand(profile="bh8-262-4.3") as hand:      # a graded hand on a fresh pty
        my_driver.open(hand.url)                    # pyserial URL (hand.port: its path)
        ...
    print(hand.verdict.failures)                    # the clauses the host broke, if any

``Hand`` runs ``gcl check-host --serve``: a simulated hand that grades the traffic of
whoever connects, clause by clause, as ``gcl check-host`` grades a host command.
``gcl.pytest_plugin`` turns it into the ``gcl_hand`` and ``gcl_misbehaving_hand`` fixtures.
Stdlib only.
"""

from ._hand import Failure, Hand, HandError, Verdict, binary

__all__ = ["Failure", "Hand", "HandError", "Verdict", "binary"]
