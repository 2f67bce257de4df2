"""Regenerate the flight code for a different quadrotor and call it from C.

`quadland codegen` writes the landing's flight code with a scenario's values as
its defaults; the flight code's model of the quadrotor is `[controller_model]`
(the plant is `[quadrotor]`). Here the highway scenario's quadrotor is made 50 %
heavier (3 kg) in both, the tree is written to a folder of its own, and examples/hover.c, compiled
against it with the C compiler, runs one period of guidance and landing step
at the hover point: the four rotor commands share the new weight.

Run: python examples/flight_code_for_another_quadrotor.py [OUT]
"""

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(out: Path, mass: float = 3.0) -> list[float]:
    subprocess.run([sys.executable, "-m", "quadland", "codegen", "--scenario", "highway",
                    "--set", f"quadrotor.mass={mass}", "--set", f"controller_model.mass={mass}",
                    "--out", str(out)], check=True)
    # the landing's sources, as the tree's own example Makefile lists them
    makefile = (out / "example" / "Makefile").read_text()
    sources = [*re.search(r"^LAND = (.*)$", makefile, re.M).group(1).split(),
               *re.search(r"^COMMON = (.*)$", makefile, re.M).group(1).split()]
    exe = out / "hover"
    cc = shutil.which("cc") or shutil.which("gcc")
    subprocess.run([cc, "-std=c99", "-O2", "-Wall", "-Werror", f"-I{out}", "-o", str(exe),
                    str(HERE / "hover.c"), *(str(out / s) for s in sources), "-lm"],
                   check=True)
    forces = [float(v) for v in subprocess.run([str(exe)], check=True, capture_output=True,
                                                text=True).stdout.split()]
    print(f"rotor commands at hover for a {mass:g} kg quadrotor: "
          f"{', '.join(f'{f:.4f}' for f in forces[:4])} N; total {forces[4]:.4f} N "
          f"(m g = {mass * 9.8:.4f} N)")
    return forces


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp()) / "tree")
