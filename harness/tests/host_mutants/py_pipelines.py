"""Mutant: sends the next commands before the prompt of the one before (to save round trips),
then reads all the answers.
Expected finding: violation of host-waits-for-answer (check-host flags it too)."""
import gclhost


def scenario(port):
    gclhost.sync(port)
    port.write(b"".join(l.encode() + b"\r" for l in gclhost.SCENARIO[:3]))
    for _ in gclhost.SCENARIO[:3]:
        gclhost.read_until(port, gclhost.PROMPT)


gclhost.main(scenario)
