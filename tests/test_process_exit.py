"""quadland.__main__.run: the process exits with the command's status, its heap frozen
(no last collection walks it), its exit handlers run, and what a command writes is
complete."""

from __future__ import annotations

import json
import subprocess
import sys

PNG = b"\x89PNG\r\n\x1a\n"


def test_run_exits_with_the_status_its_heap_frozen_and_the_exit_handlers_run():
    code = """
import atexit, gc, sys, weakref
import quadland.__main__ as entry

class Node:
    pass

a, b = Node(), Node()
a.other, b.other = b, a                     # alive in a cycle at exit
weakref.finalize(a, print, "finalized")     # run at exit (atexit=True)
atexit.register(lambda: print("frozen", gc.get_freeze_count() > 0))
entry.main = lambda argv=None, process=False: 3 if process else 4   # 3: as the process
entry.run()
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 3, proc.stderr
    assert proc.stdout.split("\n")[:2] == ["frozen True", "finalized"], proc.stdout


def test_margins_writes_everything_through_the_process_entry(tmp_path):
    out = tmp_path / "margins"
    proc = subprocess.run([sys.executable, "-m", "quadland", "margins", "--scenario", "paper",
                           "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads((out / "margins.json").read_text())["requirement"]
    for name in ("bode.png", "nyquist.png", "nichols.png", "sigma.png", "poles.png"):
        data = (out / name).read_bytes()
        assert data[:8] == PNG and data.endswith(b"IEND\xaeB`\x82")


def test_a_reader_that_stops_early_ends_the_command_quietly(tmp_path):
    """``quadland margins ... | head -1``: the review prints a line per stage, flushed; the
    pipe closed after the first, the next write fails. The process ends with 128 + SIGPIPE
    and no traceback, as a Unix tool would."""
    proc = subprocess.Popen([sys.executable, "-m", "quadland", "margins", "--scenario", "paper",
                             "--no-plots", "--out", str(tmp_path / "m")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    first = proc.stdout.readline()
    proc.stdout.close()                     # the reader goes away after one line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 141, err
    assert first and "Traceback" not in err and "BrokenPipe" not in err, err
