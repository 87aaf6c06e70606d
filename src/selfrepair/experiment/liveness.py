"""Whether a registered writer of the results store is still alive: its heartbeat, and on the
same host its process (which may have died, become a zombie, or had its pid reused)."""

from __future__ import annotations

import os
import socket
from pathlib import Path

__all__ = ["LEASE_SECONDS", "process_start", "writer_is_dead"]

LEASE_SECONDS = 300.0
"""A writer whose heartbeat is older than this is taken for dead and its claims are free again.
Writers beat at least every few seconds while they run (see the runner), so only a dead or hung
writer, or one on another host that cannot be asked directly, ever reaches it."""


def writer_is_dead(host: str, pid: int, pid_start: object, heartbeat: float, now: float) -> bool:
    """Whether a registered writer is gone: silent for longer than the lease, or (same host)
    its process no longer exists, is a zombie, or is another process that reused the pid."""
    if now - heartbeat > LEASE_SECONDS:
        return True
    if host != socket.gethostname():
        return False
    if not _pid_alive(pid):
        return True
    start = process_start(pid)
    return pid_start is not None and start is not None and start != pid_start


def _pid_alive(pid: int) -> bool:
    stat = Path(f"/proc/{pid}/stat")
    if Path("/proc/self/stat").exists():
        try:
            state = stat.read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            return False
        return state not in ("Z", "X")
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def process_start(pid: int) -> str | None:
    """When process ``pid`` started (clock ticks since boot, from /proc), to tell a reused pid;
    ``None`` where /proc is not available."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None
