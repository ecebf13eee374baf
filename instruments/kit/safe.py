"""The confirmed safe state: the one safe-state procedure of every output driver.

:func:`confirmed_safe_state` switches the output off over a link that may have misbehaved, then
reads the output state back, twice if need be, and reports failure only when neither attempt
confirmed the output off. :func:`output_found_on` reads, before anything else is sent, whether
an output was left on (by a run that died). :class:`~fsi_lab.instruments.kit.scpi.ScpiOutput`
uses both; a driver of another protocol calls them itself.
"""

from __future__ import annotations

from collections.abc import Callable

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


def output_found_on(link, query: str, timeout_s: float = SAFE_TIMEOUT_S) -> bool | None:
    """Whether an output was left on: ``query`` (``"OUTP?"``) before anything else is sent.

    Returns None when the reply could not be read; the link is then reopened, so that the
    command switching the output off still goes out.

    Parameters
    ----------
    link
        The :class:`~fsi_lab.instruments._visa.VisaLink`.
    query
        The query of the output state, answered 0/1 or OFF/ON.
    timeout_s
        Time allowed for the reply, s.
    """
    try:
        with link.timeout(timeout_s):
            return link.query_bool(query)
    except InstrumentError:
        link.recover(timeout_s)
        return None
