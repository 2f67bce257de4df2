"""The fixed costs of a command: BLAS threads, the build's cache key, lazy figures."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

_BLAS_THREADS = """
from quadland.__main__ import main
main(["scenarios"])
import json, numpy, scipy.linalg
from threadpoolctl import threadpool_info
print(json.dumps(sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")))
"""


@pytest.mark.slow
@pytest.mark.parametrize("given, expected", [(None, 1), ("2", 2)])
def test_the_command_line_asks_blas_for_one_thread_unless_told(given, expected):
    """Both OpenBLAS libraries (NumPy's and SciPy's, loaded after the command
    started) run one thread; a count in the environment is kept."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS")}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    out = subprocess.run([sys.executable, "-c", _BLAS_THREADS], capture_output=True, text=True,
                         env=env, check=True)
    counts = json.loads(out.stdout.strip().splitlines()[-1])
    assert counts and counts == [expected] * len(counts)
