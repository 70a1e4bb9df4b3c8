"""A Ray cluster of real nodes on this machine for the tests, started with Ray's own CLI and stopped to its last
process.

``python ray_cluster.py TEMP_DIR PORT CPUS [CPUS ...]`` starts a head node (``ray start --head``) with the first
CPUS and one more node (``ray start --address``) per further CPUS, all on 127.0.0.1 and under TEMP_DIR, prints
``ready`` and waits for its standard input to close. Then it stops every process it started, and only those: it
makes itself their subreaper (Linux), so the daemons ``ray start`` leaves behind become its children instead of
init's, where ``ray stop`` would find (and stop) every Ray process of the machine, other users' too.
"""

from __future__ import annotations

import ctypes
import subprocess
import sys
from pathlib import Path

import psutil

PR_SET_CHILD_SUBREAPER = 36


def stop_descendants() -> None:
    children = psutil.Process().children(recursive=True)
    for child in children:
        child.terminate()
    _, alive = psutil.wait_procs(children, timeout=15)
    for child in alive:
        child.kill()
    psutil.wait_procs(alive, timeout=15)


def main(temp_dir: str, port: str, cpus: list[str]) -> None:
    if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER) failed")
    ray = str(Path(sys.executable).with_name("ray"))
    common = ["--node-ip-address", "127.0.0.1", "--temp-dir", temp_dir, "--disable-usage-stats"]
    try:
        subprocess.run([ray, "start", "--head", "--port", port, "--num-cpus", cpus[0], "--include-dashboard",
                        "false", *common], check=True, stdout=subprocess.DEVNULL)
        for n in cpus[1:]:
            subprocess.run([ray, "start", "--address", f"127.0.0.1:{port}", "--num-cpus", n, *common], check=True,
                           stdout=subprocess.DEVNULL)
        print("ready", flush=True)
        sys.stdin.read()
    finally:
        stop_descendants()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
