"""Opening, safing and closing a profile's instruments, in a run or outside one.

The runner, the ``fsi-lab safe`` and ``fsi-lab identify`` commands and the GUI's bench panel
share these steps, so the safe state is reached the same way everywhere: every opened
instrument is put in its safe state in :data:`SAFE_ORDER` (the amplifier first), its state is
read back, it is closed, and what the simulated bench registered for cleanup is stopped. A
failure of one instrument is recorded and the others are still made safe.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from fsi_lab.contract import PURPOSES, ROLE_INTERFACES, BenchContext, Instrument  # noqa: F401 - re-exported for drivers
from fsi_lab.profile import Profile
from fsi_lab.registry import Registry
from fsi_lab.signals import RunSignals

#: Roles whose output can drive the shaker (``has_output``): their ``read_state()`` must say
#: ``output_enabled``.
OUTPUT_ROLES = tuple(role for role, cls in ROLE_INTERFACES.items() if cls.has_output)
#: Instruments are put in their safe state in this order: the amplifier first.
SAFE_ORDER = ("amplifier", "source", "vibrometer", "acquisition")
#: And opened in this order: the amplifier first, so it can be made safe before anything else.
OPEN_ORDER = ("amplifier", "source", "vibrometer", "acquisition")

Log = Callable[[str, str], None]


def bench_context(profile: Profile, purpose: str = "run") -> BenchContext:
    """The :class:`~fsi_lab.contract.BenchContext` shared by the instruments of one profile:
    its ``specimen``, ``model``, ``shaker`` and ``bench`` sections, an empty ``cleanup`` list
    and the ``purpose`` the instruments are opened for (:data:`PURPOSES`; ValueError for
    another)."""
    return BenchContext(specimen=profile.specimen, model=profile.model, shaker=profile.shaker,
                        bench=dict(profile.bench), purpose=purpose)


def _plugins(profile: Profile) -> dict[str, str]:
    """The plugin name of each role of ``profile`` (for messages)."""
    return {role: config.plugin for role, config in profile.roles.items()}


def safe_and_close(instruments: Mapping[str, Instrument], cleanup: list[Callable[[], None]],
                   log: Log = lambda level, text: None,
                   plugins: Mapping[str, str] | None = None) -> dict[str, dict[str, Any]]:
    """Safe state for every instrument (amplifier first), then read its state back and close it.

    An instrument whose safe state failed, or whose state read back still has its output on
    (a link that hiccuped), gets one more attempt before it is closed.

    Parameters
    ----------
    instruments
        Opened instruments by role.
    cleanup
        Callables run last, in reverse order (simulated benches stop their servers there).
    log
        ``log(level, text)`` for what went wrong.
    plugins
        The plugin (driver) name of each role, which messages name (default: the class name of
        the instrument).

    Returns
    -------
    dict
        Per role, the state read back; ``error`` when it could not be read and
        ``safe_state_error`` when the safe state failed (see :func:`unsafe_roles`).
    """
    opened = [(role, instruments[role]) for role in SAFE_ORDER if role in instruments]
    names = {role: (plugins or {}).get(role) or type(instrument).__name__
             for role, instrument in opened}
    errors = {role: _safe_state(instrument) for role, instrument in opened}
    states = {role: _read_state(instrument) for role, instrument in opened}

    def unconfirmed(role: str) -> str:
        return _output_unconfirmed(role, states[role], names[role])

    for role, instrument in opened:
        if errors[role] is None and not unconfirmed(role):
            continue
        log("ERROR", f"{role}: {errors[role] or unconfirmed(role)}; trying once more")
        errors[role] = _safe_state(instrument)
        states[role] = _read_state(instrument)
        if errors[role] is None and unconfirmed(role):
            errors[role] = "safe state failed: " + unconfirmed(role) + " after two attempts"
        if errors[role] is not None:
            states[role]["safe_state_error"] = errors[role]
            log("ERROR", f"{role}: NOT confirmed safe: {errors[role]}")
    for role, instrument in opened:
        try:
            instrument.close()
        except Exception as exc:  # noqa: BLE001 - a driver's close must not stop the others
            log("WARNING", f"{role}: close failed: {exc}")
    for stop in reversed(cleanup):
        try:
            stop()
        except Exception as exc:  # noqa: BLE001 - every cleanup runs, whatever one raises
            log("WARNING", f"bench cleanup failed: {exc}")
    return states


def _safe_state(instrument: Instrument) -> str | None:
    """Put ``instrument`` in its safe state; what went wrong, or None."""
    try:
        instrument.safe_state()
    except Exception as exc:  # noqa: BLE001 - keep going: the others must be safed too
        return f"safe state failed: {type(exc).__name__}: {exc}"
    return None


def _read_state(instrument: Instrument) -> dict[str, Any]:
    try:
        return dict(instrument.read_state())
    except Exception as exc:  # noqa: BLE001 - a dead driver's state is reported, not raised
        return {"error": f"could not read state: {type(exc).__name__}: {exc}"}


def _output_unconfirmed(role: str, state: Mapping[str, Any], plugin: str = "") -> str:
    """Why ``state`` read back does not confirm the output off, or ''. An output role
    (:data:`OUTPUT_ROLES`) must report ``output_enabled`` False; a state without it (a driver
    that forgot the key, or a state that could not be read) confirms nothing, and the message
    names the driver (``plugin``)."""
    enabled = state.get("output_enabled")
    if enabled is True:
        return "the output is still on"
    if role in OUTPUT_ROLES and enabled is not False:
        if "error" in state:
            return str(state["error"])
        driver = f"driver {plugin!r}: " if plugin else ""
        got = "no output_enabled" if "output_enabled" not in state \
            else f"output_enabled = {enabled!r}, not a bool"
        return (f"{driver}its state read back does not say that the output is off "
                f"(read_state() gives {got}; a driver of the {role} role returns "
                "fsi_lab.contract.OutputState(output_enabled=<bool read from the instrument>))")
    return ""


def unsafe_roles(states: Mapping[str, Mapping[str, Any]],
                 plugins: Mapping[str, str] | None = None) -> dict[str, str]:
    """Per role, why an instrument of :func:`safe_and_close` is not confirmed safe: its safe
    state failed, it still reports its output on, or (an output role) its state does not say
    that the output is off (naming the driver from ``plugins``, role -> plugin name)."""
    found = {}
    for role, state in states.items():
        why = _output_unconfirmed(role, state, (plugins or {}).get(role, ""))
        if "safe_state_error" in state:
            found[role] = str(state["safe_state_error"])
        elif why:
            found[role] = why
    return found


def each_instrument(profile: Profile, registry: Registry, order: tuple[str, ...],
                    action: Callable[[str, Instrument], dict[str, Any]],
                    log: Log = lambda level, text: None) -> dict[str, dict[str, Any]]:
    """Open every instrument of ``profile`` in ``order`` and apply ``action`` to it; then make
    all of them safe and close them (:func:`safe_and_close`).

    Returns, per role, what ``action`` returned (or ``error`` if opening or the action failed)
    with the ``state`` read back after the safe state (and ``safe_state_error`` if it failed);
    ``log(level, text)`` hears of failed closes and cleanups. Ctrl+C or SIGTERM (in the main
    thread) is held until every instrument has been made safe, then raised as
    :class:`BenchInterrupted`, which carries the report.
    """
    context = bench_context(profile, "outside-run")
    opened: dict[str, Instrument] = {}
    report: dict[str, dict[str, Any]] = {}
    signals = RunSignals()  # Ctrl+C and SIGTERM wait until every instrument has been seen to
    signals.install()
    try:
        with signals.held():
            try:
                for role in order:
                    config = profile.roles.get(role)
                    if config is None:
                        continue
                    try:
                        descriptor = registry.get("instrument", config.plugin)
                        opened[role] = descriptor.open(config.address, dict(config.settings),
                                                       context)
                        found_on = getattr(opened[role], "found_on", None)
                        report[role] = action(role, opened[role])
                        if found_on:
                            report[role]["output_found_on"] = True
                            log("WARNING", f"{role}: its output was ON when opened (left on by a "
                                           "run that died?); it was switched off")
                    except Exception as exc:  # noqa: BLE001 - reported per instrument
                        report[role] = {"error": f"{type(exc).__name__}: {exc}"}
            finally:
                states = safe_and_close(opened, context.cleanup, log, _plugins(profile))
                for role, state in states.items():
                    safe_error = state.pop("safe_state_error", None)
                    report.setdefault(role, {}).setdefault("state", state)
                    if safe_error:
                        report[role]["safe_state_error"] = safe_error
    finally:
        signals.restore()
    if signals.pending:
        log("WARNING", "interrupted: every instrument was still made safe first")
        raise BenchInterrupted(report)
    return report


class BenchInterrupted(KeyboardInterrupt):
    """Ctrl+C or SIGTERM arrived while :func:`each_instrument` worked; ``report`` is what it
    found, every instrument having been made safe all the same."""

    def __init__(self, report: dict[str, dict[str, Any]]) -> None:
        super().__init__("interrupted")
        self.report = report


def problems(report: Mapping[str, Mapping[str, Any]]) -> dict[str, str]:
    """Per role, what went wrong in a report of :func:`each_instrument` (opening or querying
    it, its safe state, reading its state back); roles without a problem are left out."""
    found: dict[str, str] = {}
    for role, info in report.items():
        texts = [str(info[key]) for key in ("error", "safe_state_error") if key in info]
        state = info.get("state")
        if isinstance(state, Mapping) and "error" in state:
            texts.append(str(state["error"]))
        if texts:
            found[role] = "; ".join(texts)
    return found


def probe_bench(profile: Profile, registry: Registry,
                log: Log = lambda level, text: None) -> dict[str, dict[str, Any]]:
    """Identity, settings and interlocks of every instrument; each is left safe and closed."""

    def probe(role: str, instrument: Instrument) -> dict[str, Any]:
        info: dict[str, Any] = {"identity": instrument.identify(),
                                "settings": dict(instrument.settings())}
        if hasattr(instrument, "interlocks"):
            info["interlocks"] = dict(instrument.interlocks())
        return info

    return each_instrument(profile, registry, OPEN_ORDER, probe, log)


def safe_bench(profile: Profile, registry: Registry,
               log: Log = lambda level, text: None) -> dict[str, dict[str, Any]]:
    """Put every instrument in its safe state (amplifier first) and read the state back; then,
    if every output instrument is confirmed safe, release the bench locks of runs that died
    (:func:`fsi_lab.bench_lock.release_dead`)."""
    from fsi_lab.bench_lock import LOCKED_ROLES, release_dead

    report = each_instrument(profile, registry, SAFE_ORDER, lambda role, instrument: {}, log)
    if not any(role in problems(report) for role in LOCKED_ROLES):
        for holder in release_dead(profile):
            log("WARNING", f"released the bench lock of a run that never finished "
                           f"({holder.describe()})")
    return report
