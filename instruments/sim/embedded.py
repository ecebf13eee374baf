"""The embedded bench: a :class:`~.bench.SimBench` started inside the fsi-lab process.

When a profile says ``[bench] embedded = true``, drivers whose address is ``"embedded"`` (or
empty) call :func:`resolve_address`. The first one starts the bench from the run's shared
context (physics from ``specimen``, ``model`` and ``shaker``; ``fast``, ``fault``,
``fault_after_s`` and ``fault_target`` from ``bench``; its integrator loaded at start only when
the ``purpose`` is a run), stores it there and registers its ``stop`` in the context's
``cleanup`` list, which the runner calls once every instrument is safe and closed. The drivers
then connect to it through their real protocol.
"""

from __future__ import annotations

from typing import Any

from fsi_lab.errors import InstrumentError

CONTEXT_KEY = "sim_bench"
EMBEDDED = ("", "embedded")


def get_embedded_bench(context: dict[str, Any]):
    """The run's embedded bench, started on first use."""
    from fsi_lab.instruments.sim.bench import BenchOptions, SimBench

    bench = context.get(CONTEXT_KEY)
    if bench is not None:
        return bench
    if context.get("specimen") is None:
        raise InstrumentError(f"embedded simulated bench: {NO_SPECIMEN}")
    section = context.get("bench") or {}
    options = BenchOptions(fast=bool(section.get("fast", False)),
                           fault=str(section.get("fault", "none")),
                           fault_after_s=float(section.get("fault_after_s", 1.0)),
                           fault_target=section.get("fault_target") or None,
                           seed=int(section.get("seed", 0)),
                           warm_up=context.get("purpose", "run") == "run")
    bench = SimBench(context["specimen"], context.get("model"), context.get("shaker"),
                     options).start()
    context[CONTEXT_KEY] = bench
    context.setdefault("cleanup", []).append(bench.stop)
    return bench


def resolve_address(role: str, plugin: str, address: str, context: dict[str, Any],
                    key: str | None = None) -> str:
    """``address`` itself, or the embedded bench's address for ``role`` (``key`` picks another
    of :attr:`SimBench.addresses`) when ``address`` is "embedded" or empty."""
    if address.strip() not in EMBEDDED:
        return address
    if not (context.get("bench") or {}).get("embedded"):
        raise InstrumentError(f"{plugin} ({role}): {_not_started(address)}")
    return get_embedded_bench(context).addresses[key or role]


NO_SPECIMEN = ("the profile has no [specimen]; the bench needs the beam whose response it "
               "simulates")


def _not_started(address: str) -> str:
    return (f"address {address!r} names the embedded simulated bench, but the profile does not "
            "say [bench] embedded = true; give the instrument's address or set embedded = true")


def check_embedded(address: str, plan: dict[str, Any]) -> bool:
    """For a driver's ``check``: whether ``address`` names the embedded bench, which the
    profile must then start and give a ``[specimen]`` (ValueError otherwise)."""
    if address.strip() not in EMBEDDED:
        return False
    if not (plan.get("bench") or {}).get("embedded"):
        raise ValueError(_not_started(address))
    if plan.get("specimen") is None:
        raise ValueError(f"address {address!r} names the embedded simulated bench, but "
                         f"{NO_SPECIMEN}")
    return True


def check_embedded_record(address: str, plan: dict[str, Any]) -> None:
    """:func:`check_embedded`, and the bench's simulated world must resolve every mode of the
    profile's beam model at the record's sample rate (ValueError naming the remedy)."""
    if not check_embedded(address, plan):
        return
    from fsi_lab.instruments.sim.rates import oversampling
    from fsi_lab.modelling import beam_model

    oversampling(beam_model(plan["specimen"], plan["model"]), plan["sample_rate"])
