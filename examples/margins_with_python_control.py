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


def main(scenario: str = "paper") -> dict[str, dict[str, tuple[float, float]]]:
    """Each loop's margins by python-control and by quadland: ``{loop: {"phase margin deg":
    (python-control, quadland), "gain margin dB": (...), "gain margin rad/s": (...)}}``."""
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
        gm, pm, _, w_180, _, _ = control.stability_margins(Li)
        mine = report.continuous.loop(name)
        # python-control gives the gain margin nearest 1 of every -180 deg crossing;
        # quadland the nearest above (up) and below (down): the one at the same crossing
        up = mine.gain_margin_up_frequency is not None and \
            abs(mine.gain_margin_up_frequency - w_180) <= 1e-6 * w_180
        ours_db, ours_w = ((mine.gain_margin_up_db, mine.gain_margin_up_frequency) if up else
                           (mine.gain_margin_down_db, mine.gain_margin_down_frequency))
        out[name] = {"phase margin deg": (pm, mine.phase_margin_deg),
                     "gain margin dB": (20 * np.log10(gm), ours_db),
                     "gain margin rad/s": (w_180, ours_w)}
        print(f"{name:>9}: phase margin python-control {pm:6.2f} deg, quadland "
              f"{mine.phase_margin_deg:6.2f} deg; gain margin python-control "
              f"{20 * np.log10(gm):+6.2f} dB at {w_180:.4g} rad/s, quadland {ours_db:+6.2f} dB "
              f"at {ours_w:.4g} rad/s")
    return out

if __name__ == "__main__":
    main()
