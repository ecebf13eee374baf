"""What fsi-lab's SCPI output drivers share, for drivers of other instruments too.

:func:`confirmed_safe_state` is the one safe-state procedure of every output driver (the
generator's and the amplifier's): switch the output off over a link that may have misbehaved,
then read the output state back, twice if need be, and report failure only when neither attempt
confirmed the output off.
"""

from __future__ import annotations

from typing import Callable

from fsi_lab.errors import InstrumentError

#: Time allowed for each reply during a safe state, s (short: a dead link must not delay it).
SAFE_TIMEOUT_S = 1.0


def confirmed_safe_state(name: str, where: str, link, switch_off: Callable[[], None],
                         output_on: Callable[[], bool], attempts: int = 2,
                         timeout_s: float = SAFE_TIMEOUT_S) -> None:
    """Switch an output off and confirm it by reading it back.

    Each attempt reconnects first if an earlier exchange left the link out of step
    (:meth:`~fsi_lab.instruments._visa.VisaLink.recover`), with replies limited to
    ``timeout_s``, runs ``switch_off`` and then asks ``output_on``.

    Parameters
    ----------
    name
        The driver's name, which starts the error message.
    where
        The instrument and its address, for messages (``"keysight33500 at TCPIP0::..."``).
    link
        The :class:`~fsi_lab.instruments._visa.VisaLink` (or anything with ``timeout``,
        ``recover`` and ``broken``).
    switch_off
        Sends what switches the output off (no reply expected).
    output_on
        Reads the output state back from the instrument.
    attempts
        Attempts before giving up.
    timeout_s
        Time allowed for each reply, s.

    Raises
    ------
    InstrumentError
        ``"<name>: safe state not confirmed: <what went wrong last>"``.
    """
    last: Exception | None = None
    for _ in range(attempts):
        try:
            with link.timeout(timeout_s):
                link.recover(timeout_s)
                switch_off()
                if not output_on():
                    return
                last = InstrumentError(f"{where}: the output still reads on after it was "
                                       "switched off")
        except InstrumentError as exc:
            last = exc
            link.broken = link.broken or str(exc)
    raise InstrumentError(f"{name}: safe state not confirmed: {last}")
