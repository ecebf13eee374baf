"""``fsi-lab bench``: run the simulated bench until Ctrl+C or SIGTERM.

It prints where each instrument answers (TCP on 127.0.0.1, pseudo-terminals for the serial
ones) and the ``[bench.*]`` tables of a profile that uses them; such a profile runs unchanged
against real hardware once the addresses are replaced. The physics is the profile's given on
the command line (``fsi-lab bench PROFILE``): its ``[specimen]``, ``[model]`` and ``[shaker]``,
and the ``fast``/``fault`` keys of ``[bench]``; run that profile (with the printed addresses)
against the bench and the analysis finds the beam the profile describes.

This module is a plugin of the ``fsi_lab`` entry-point group (``sim-bench``): it adds the command
through the ``fsi_lab_addcommands`` hook, and is imported whenever ``fsi-lab`` starts, so
everything heavy is imported inside :func:`run`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fsi_lab.contract import CliCommand
from fsi_lab.hookspecs import hookimpl
from fsi_lab.instruments.sim.faults import FAULTS, ROLES


def profile_snippet(bench) -> str:
    """``[bench.*]`` tables of a profile that uses the running simulated ``bench`` with
    fsi-lab's lab drivers (the simulator itself knows no driver)."""
    from fsi_lab.instruments.keysight33500 import PLUGIN as SOURCE
    from fsi_lab.instruments.polytec import PLUGIN as VIBROMETER
    from fsi_lab.instruments.scpi_daq import PLUGIN as ACQUISITION
    from fsi_lab.instruments.shaker_amplifier import PLUGIN as AMPLIFIER

    a = bench.addresses
    return "\n".join([
        "[bench.source]", f'plugin = "{SOURCE.name}"', f'address = "{a["source"]}"', "",
        "[bench.amplifier]", f'plugin = "{AMPLIFIER.name}"', f'address = "{a["amplifier"]}"',
        "gain = 2.0", "",
        "[bench.vibrometer]", f'plugin = "{VIBROMETER.name}"',
        f'address = "{a["vibrometer"]}"', 'range = "125mm/s/V"', "",
        "[bench.acquisition]", f'plugin = "{ACQUISITION.name}"',
        f'address = "{a["acquisition"]}"', ""])


def configure(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``fsi-lab bench`` to ``parser``."""
    parser.add_argument("profile", type=Path, metavar="PROFILE",
                        help="the profile whose beam ([specimen], [model]), shaker and [bench] "
                             "fast/fault keys the bench simulates")
    parser.add_argument("--fast", action="store_true", default=None,
                        help="simulate as fast as the client fetches (default: real time)")
    parser.add_argument("--fault", choices=FAULTS, help="inject this fault")
    parser.add_argument("--fault-after", type=float, metavar="S",
                        help="record time at which the fault happens (default 1 s)")
    parser.add_argument("--fault-target", choices=ROLES,
                        help="instrument whose link a timeout, drop or garble hits "
                             "(default: the profile's [bench] fault_target, acquisition)")
    for role in ("source", "amplifier", "acquisition"):
        parser.add_argument(f"--{role}-port", type=int, default=0, metavar="PORT",
                            help=f"TCP port of the {role} on 127.0.0.1 (default: any free port)")
    parser.add_argument("--source-channel", type=int, choices=(1, 2), default=1,
                        help="the generator's channel wired to the amplifier (default 1)")
    parser.add_argument("--seed", type=int, default=None,
                        help="seed of the noise generators (default: the profile's [bench] seed)")
    parser.add_argument("--json", action="store_true",
                        help="print the addresses and the profile snippet as one JSON line")
    parser.add_argument("-q", "--quiet", action="store_true", help="no event log on stderr")


def _profile_sections(path: Path):
    """Specimen, model, shaker and the [bench] keys of a profile (ProfileError if invalid or
    without a [specimen])."""
    from fsi_lab.errors import ProfileError
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry

    profile = load_profile(path, load_registry(),
                           sections=("specimen", "model", "shaker", "bench"))
    if profile.specimen is None:
        raise ProfileError(f"{path}: specimen: missing; the simulated bench needs the beam whose "
                           "response it simulates ([specimen], and [model] for its damping)")
    return profile.specimen, profile.model, profile.shaker, profile.bench


def run(args: argparse.Namespace) -> int:
    """Start the bench, print its addresses, serve until SIGINT or SIGTERM; the exit code."""
    import json
    import signal
    import threading

    from fsi_lab.errors import FsiLabError
    from fsi_lab.instruments.sim.bench import BenchOptions, SimBench

    try:
        specimen, model, shaker, bench_keys = _profile_sections(args.profile)
    except FsiLabError as exc:
        print(f"fsi-lab: error: {exc}", file=sys.stderr)
        return exc.exit_code

    def log(text: str) -> None:
        if not args.quiet:
            print(f"[bench] {text}", file=sys.stderr, flush=True)

    options = BenchOptions(
        fast=bench_keys["fast"] if args.fast is None else True,
        fault=args.fault or bench_keys["fault"],
        fault_after_s=bench_keys["fault_after_s"] if args.fault_after is None else args.fault_after,
        fault_target=args.fault_target or bench_keys.get("fault_target"),
        seed=bench_keys["seed"] if args.seed is None else args.seed,
        source_channel=args.source_channel,
        ports={"source": args.source_port, "amplifier": args.amplifier_port,
               "acquisition": args.acquisition_port},
        log=log)
    stop = threading.Event()
    previous = {sig: signal.signal(sig, lambda signum, frame: stop.set())
                for sig in (signal.SIGINT, signal.SIGTERM)}
    bench = SimBench(specimen, model, shaker, options)
    try:
        bench.start()
    except OSError as exc:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        print(f"fsi-lab: error: cannot start the simulated bench: {exc}", file=sys.stderr)
        return 1
    try:
        addresses, snippet = bench.addresses, profile_snippet(bench)
        if args.json:
            print(json.dumps({"addresses": addresses, "profile": snippet}), flush=True)
        else:
            print("simulated bench (Ctrl+C stops it):")
            for role, address in addresses.items():
                print(f"  {role:<17} {address}")
            print("\nprofile tables for these instruments:\n")
            print(snippet, flush=True)
        while not stop.wait(0.5):
            pass
    finally:
        bench.stop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        log("stopped")
    return 0


COMMAND = CliCommand(
    name="bench",
    help="start the simulated bench (instruments on 127.0.0.1 and pseudo-terminals)",
    configure=configure,
    run=run,
)


@hookimpl
def fsi_lab_addcommands(subparsers) -> None:
    """``fsi-lab bench``."""
    COMMAND.add_to(subparsers)


def main(argv: list[str] | None = None) -> int:
    """``python -m fsi_lab.instruments.sim.cli`` does what ``fsi-lab bench`` does."""
    parser = argparse.ArgumentParser(prog="fsi-lab bench", description=COMMAND.help)
    configure(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
