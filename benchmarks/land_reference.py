"""The pure-C reference of issue 20's campaign targets: ``generated/example/land -q`` (the
whole landing in C, the touchdown report alone), timed by the child's own rusage."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "generated" / "example"


def land_q(repeats: int) -> list[float]:
    """CPU seconds of each ``land -q`` (the child's rusage), built first if it is not."""
    subprocess.run(["make", "-s", "build/land"], cwd=EXAMPLE, check=True)
    out = []
    for _ in range(repeats):
        proc = subprocess.Popen([str(EXAMPLE / "build" / "land"), "-q"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(proc.pid, 0)
        assert os.waitstatus_to_exitcode(status) == 0
        out.append(usage.ru_utime + usage.ru_stime)
    return out
