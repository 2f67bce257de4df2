"""Tune a gain and watch the margins and a landing change.

The highway landing's outer-loop gain k1p sets how fast the position loop is. A
softer gain buys a little phase margin in roll and pitch (tenths of a degree: the
attitude loops, about 60 deg with one period of computation delay, are set by the
inner gains k1 and k2) at the price of a slower approach (k1p = 1 touches down
about 6 s later than 1.5). For each value, this script prints the sampled loop's
roll and pitch phase margins and the landing's touchdown time and sink rate.

Run: python examples/tune_a_gain.py
"""

import quadland
from quadland.kinds.landing.report import touchdown_report


def main(gains=(1.0, 1.5, 2.0)) -> list[tuple[float, float, float, float, bool]]:
    rows = []
    for k in gains:
        # 80 s: with the real drag the softest gain aborts its descent three times and
        # touches down at 45 s (docs/landing.md, "Real drag and thrust")
        sc = quadland.load_scenario("highway", [f"controller.k1p=[{k}, {k}, {k}]",
                                                "simulation.duration=80.0"])
        report = quadland.margin_report(sc)
        roll, pitch = (report.sampled.loop(n).phase_margin_deg for n in ("roll", "pitch"))
        landing = touchdown_report(quadland.simulate(sc))
        rows.append((k, roll, pitch, landing.time, landing.success))
        contact = (f"touchdown at {landing.time:5.2f} s, sink rate {landing.sink_rate:.2f} m/s"
                   if landing.touchdown else "no touchdown")
        print(f"k1p = {k:3.1f} 1/s: phase margin roll {roll:5.1f} deg, pitch {pitch:5.1f} deg; "
              f"{contact}, {'success' if landing.success else 'failed'}")
    return rows


if __name__ == "__main__":
    main()
