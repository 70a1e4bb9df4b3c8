"""What a timed job ran on: the cores, and how busy they were when it started. A wall time measured while other
work shared the cores is not the time of an idle machine, so reports that give times say which it was."""

from __future__ import annotations

import os


def machine_state() -> str:
    """The core count and the 1-minute load average now, in words, e.g. ``"2 cores, load average 0.31 at the start
    (about 0 when idle; 2 or more when other work shares the cores)"``; the cores alone where the system keeps no
    load average."""
    cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):  # Windows
        return f"{cores} cores"
    return (f"{cores} cores, load average {load:.2f} at the start (about 0 when idle; {cores} or more when other "
            "work shares the cores)")
