"""Compare quadland's margins with python-control's on the exported models.

quadland's margin report holds its linear models as python-control StateSpace
objects with named signals. Breaking the loop at one input of the plant, with
the other loops closed, python-control's own stability_margins gives the same
gain and phase margins as quadland's table.

Run: python examples/margins_with_python_control.py
"""

import control
import numpy as np

import quadland


def main(scenario: str = "paper") -> dict[str, tuple[float, float]]:
    report = quadland.margin_report(quadland.load_scenario(scenario))
    m = report.models
    # the loop transfer L = -K P broken at the plant input: K from P's outputs to its inputs
    L = -(m.controller * m.plant)          # loop_input -> loop_input, continuous time
    out = {}
    for i, name in enumerate(m.loop_names):
        # loop i open, the others closed: unity feedback on every channel but i
        K = np.eye(L.ninputs)
        K[i, i] = 0.0
        Li = control.feedback(L, K)[i, i]
        gm, pm, *_ = control.stability_margins(Li)
        mine = report.continuous.loop(name)
        out[name] = (pm, mine.phase_margin_deg)
        print(f"{name:>9}: phase margin python-control {pm:6.2f} deg, quadland "
              f"{mine.phase_margin_deg:6.2f} deg")
    return out


if __name__ == "__main__":
    main()
