"""The bench lock: one run at a time on a bench, and a run that died is noticed by the next one.

A run on real instruments (any address but the embedded bench) takes a lock file for the address
of each of its output instruments (source and amplifier) before it opens anything, and releases
them once the bench is in its safe state and the run file is finalised. A lock holds the pid of
its holder, the host, the start time, the profile and the run file.

A run finds the lock of an earlier one and refuses to start (exit 2, nothing opened or written):

- its holder is alive: the bench is in use;
- its holder is dead (``kill -9``, a crash, a power cut): that run never finished, so the
  outputs it drove may still be on, and nobody has looked. ``fsi-lab safe PROFILE`` makes the
  bench safe, reports what it found on, and releases such a lock.

Locks live in ``$FSI_LAB_LOCK_DIR``, else ``$XDG_STATE_HOME/fsi-lab/locks``, else
``~/.local/state/fsi-lab/locks``: on the machine that drives the bench.
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fsi_lab.errors import FsiLabError

#: The roles whose outputs can drive the shaker.
LOCKED_ROLES = ("amplifier", "source")
EMBEDDED = ("", "embedded")


class BenchBusy(FsiLabError):
    """The bench is held by another run, or by one that died (exit code 2: refused)."""

    exit_code = 2


def lock_dir() -> Path:
    """Where lock files live (see the module's description)."""
    if os.environ.get("FSI_LAB_LOCK_DIR"):
        return Path(os.environ["FSI_LAB_LOCK_DIR"])
    state = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(state) / "fsi-lab" / "locks"


def locked_addresses(profile) -> dict[str, str]:
    """Address of each output instrument of ``profile`` that is not the embedded bench, by
    role."""
    found = {}
    for role in LOCKED_ROLES:
        config = profile.roles.get(role)
        if config is not None and config.address.strip() not in EMBEDDED:
            found[role] = config.address.strip()
    return found


def _path(address: str) -> Path:
    digest = hashlib.sha1(address.encode("utf-8")).hexdigest()[:20]
    return lock_dir() / f"bench-{digest}.json"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


@dataclass
class Holder:
    """Who holds the lock on one address."""

    address: str
    path: Path
    info: dict[str, Any]

    @property
    def pid(self) -> int:
        return int(self.info.get("pid", -1))

    @property
    def alive(self) -> bool:
        """Whether the holder still runs (a lock from another host counts as alive)."""
        if self.info.get("host") not in (None, socket.gethostname()):
            return True
        return self.pid > 0 and _alive(self.pid)

    def describe(self) -> str:
        return (f"pid {self.pid} on {self.info.get('host', '?')}, started "
                f"{self.info.get('started', '?')}, run file {self.info.get('run_file') or '?'}")


def holders(addresses: dict[str, str]) -> list[Holder]:
    """The locks held on ``addresses`` (role -> address)."""
    found = []
    for address in addresses.values():
        path = _path(address)
        try:
            info = json.loads(path.read_text())
        except FileNotFoundError:
            continue
        except (OSError, ValueError):
            info = {}
        found.append(Holder(address, path, info if isinstance(info, dict) else {}))
    return found


class BenchLock:
    """The locks of one run on its output instruments' addresses.

    Parameters
    ----------
    profile
        The run's profile (:attr:`~fsi_lab.profile.Profile.roles`, ``path``).
    """

    def __init__(self, profile) -> None:
        self.profile = profile
        self.addresses = locked_addresses(profile)
        self._taken: list[Path] = []

    def acquire(self, run_file: str = "") -> None:
        """Take every lock, or none (BenchBusy naming the holder and what to do)."""
        if not self.addresses:
            return
        info = {"pid": os.getpid(), "host": socket.gethostname(),
                "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "profile": str(getattr(self.profile, "path", "")), "run_file": run_file,
                "addresses": self.addresses}
        lock_dir().mkdir(parents=True, exist_ok=True)
        try:
            for role, address in self.addresses.items():
                path = _path(address)
                try:
                    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
                except FileExistsError:
                    raise self._refusal(role, address) from None
                with os.fdopen(fd, "w") as handle:
                    json.dump(info, handle)
                self._taken.append(path)
        except BaseException:
            self.release()
            raise

    def _refusal(self, role: str, address: str) -> BenchBusy:
        found = holders({role: address})
        holder = found[0] if found else None
        where = f"{self.profile.path}: bench.{role} at {address}"
        if holder is not None and holder.alive:
            return BenchBusy(f"{where} is in use by another fsi-lab run ({holder.describe()}); "
                             "wait for it to end")
        what = holder.describe() if holder is not None else "unknown holder"
        return BenchBusy(
            f"{where}: an earlier run on this bench never finished ({what}): the outputs it "
            f"drove may still be on; run `fsi-lab safe {self.profile.path}` first (it reports "
            "what it finds on and releases the bench)")

    def release(self) -> None:
        """Remove the locks this run took (never raises)."""
        for path in self._taken:
            try:
                path.unlink()
            except OSError:
                pass
        self._taken.clear()


def release_dead(profile) -> list[Holder]:
    """Remove the locks on ``profile``'s output instruments whose holder is dead (after the
    bench was made safe); the holders removed."""
    released = []
    for holder in holders(locked_addresses(profile)):
        if holder.alive:
            continue
        try:
            holder.path.unlink()
        except OSError:
            continue
        released.append(holder)
    return released
