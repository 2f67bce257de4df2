"""The ``[landing]`` keys of the landing schema: the guidance's phases, the descent profile and
its gates (docs/landing.md; the flight code's layout is
``quadland_symbolic.landing.guidance.GUIDANCE_PARAMS``)."""

from __future__ import annotations

from quadland.schema.fields import Field

__all__ = ["GUIDANCE_FIELDS"]

F, I, B, S = float, int, bool, str
_POS = dict(lo=0.0, lo_open=True)

#: ``[landing]``'s keys, the landing schema's table of that name.
GUIDANCE_FIELDS = {
    "hover_height": Field(F, "m", "hover point: the centre's height above the pad",
                          hi=1e3, **_POS),
    "align_radius": Field(F, "m", "distance to the hover point that ends the approach",
                          hi=1e3, **_POS),
    "dwell_time": Field(F, "s", "time the align criteria must hold", lo=0.0, hi=1e3),
    "descent_speed": Field(F, "m/s", "largest descent rate", hi=100.0, **_POS),
    "descent_time": Field(F, "s", "descent rate = height above touchdown / descent_time",
                          hi=1e3, **_POS),
    "touchdown_speed": Field(F, "m/s", "descent rate of the final crawl", hi=100.0, **_POS),
    "max_deck_rise": Field(F, "m/s", "a faster rising deck aborts the committed final "
                           "descent", hi=100.0, **_POS),
    "commit_height": Field(F, "m", "height above touchdown where the descent waits for a "
                           "calm window of the deck (quiescent periods)", hi=1e3, **_POS),
    "commit_horizon": Field(F, "s", "how far ahead the deck's rise must be predicted "
                            "calm to commit the final descent", hi=100.0, **_POS),
    "calm_speed": Field(F, "m/s", "largest predicted vertical speed of the deck over the "
                        "horizon at which the final descent commits", hi=100.0, **_POS),
    "motion_time": Field(F, "s", "time constant of the deck motion's averages (the "
                         "predictor's frequency)", hi=1e4, **_POS),
    "descent_leash": Field(F, "m", "how far the falling descent reference may lead the "
                           "quadrotor down (0: no limit)", lo=0.0, hi=1e3, default=0.0),
    "leash_height": Field(F, "m", "height above touchdown below which descent_leash holds",
                          lo=0.0, hi=1e3, default=1e3),
    "withdraw_height": Field(F, "m", "reference height above touchdown at or below which "
                             "a rising deck (or a swerve) no longer withdraws the committed "
                             "descent (-1000: everywhere)", lo=-1e3, hi=1e3, default=-1e3),
    "calm_tilt_deg": Field(F, "deg", "the deck's normal predicted at the contact within "
                           "this of the flare's worst lean, or the final descent does "
                           "not commit (180: no limit)", lo=0.0, hi=180.0, default=180.0),
    "calm_lean_deg": Field(F, "deg", "the quadrotor's lean from the vertical, averaged "
                           "over lean_time, within this, or the final descent does not "
                           "commit (90: no limit)", lo=0.0, hi=90.0, default=90.0),
    "lean_time": Field(F, "s", "time constant of the lean's average for calm_lean_deg",
                       hi=1e4, default=1.0, **_POS),
    "lean_withdraw": Field(B, "-", "true: once committed, the lean past calm_lean_deg "
                           "withdraws the descent above withdraw_height, as a rising deck "
                           "does; false: it only holds the commit", default=False),
    "abort_floor": Field(F, "m", "the gear's estimated height above the deck at or below "
                         "which the crawl's out-of-limits abort is not started (-1000: "
                         "it is down to the contact)", lo=-1e3, hi=1e3, default=-1e3),
    "withdraw_budget": Field(F, "-", "once the descent's abort count (the crawl's aborts "
                             "and the commit's withdrawals) reaches this, a rising deck (or "
                             "a swerve, a gust's lean) no longer withdraws the committed "
                             "crawl (touchdown_speed x descent_time above touchdown): it "
                             "crawls on into the deck (1e6: always withdrawn)", lo=0.0,
                             hi=1e6, default=1e6),
    "crawl_abort_offset": Field(F, "m", "the crawl's out-of-limits abort is also started past "
                                "this horizontal offset, as estimated (1000: past "
                                "max_offset only; 0 is refused, it would abort every crawl)",
                                lo=0.0, lo_open=True, hi=1e3, default=1e3),
    "crawl_abort_budget": Field(F, "-", "crawl_abort_offset holds while the descent's abort "
                                "count (the crawl's aborts and the commit's withdrawals) is "
                                "below this; from then on max_offset alone (1e6: always; 0: "
                                "never)", lo=0.0, hi=1e6, default=1e6),
    "crawl_pause": Field(B, "-", "true: out of the align band the crawl pauses as the "
                         "descent above it does; false: it is committed", default=False),
    "swerve_accel": Field(F, "m/s^2", "the pad's horizontal acceleration (as the "
                          "aircraft knows it) above which the final descent does not "
                          "commit and a committed one is withdrawn (0: no hold)",
                          lo=0.0, hi=100.0, default=0.0),
    "crawl_gate": Field(F, "m", "the crawl pauses while the horizontal offset predicted "
                        "at the contact (estimate + velocity x time to contact) lies "
                        "farther than this from the pad (0: no gate)", lo=0.0, hi=100.0,
                        default=0.0),
    "crawl_gate_time": Field(F, "s", "the longest time to contact over which crawl_gate's "
                             "prediction carries the estimated velocity", lo=0.0, hi=1e3,
                             default=1e3),
    "crawl_gate_floor": Field(F, "m", "reference height above touchdown at or below which "
                              "crawl_gate no longer pauses the crawl", lo=0.0, hi=1e3,
                              default=0.0),
    "crawl_gate_rise": Field(F, "m/s", "crawl_gate holds the crawl only while the deck's "
                             "vertical speed at the pad is within this (a quiescent "
                             "deck)", lo=0.0, hi=1e3, default=1e3),
    "crawl_gate_wait_height": Field(F, "m", "height above touchdown at or below which "
                                    "crawl_gate_wait applies", lo=0.0, hi=1e3, default=1e3),
    "crawl_gate_count_height": Field(F, "m", "height above touchdown at or below which "
                                     "crawl_gate's holds count toward crawl_gate_wait",
                                     lo=0.0, hi=1e3, default=1e3),
    "crawl_gate_wait": Field(F, "s", "the longest crawl_gate holds a crawl: it falls on "
                             "at or below crawl_gate_wait_height", lo=0, hi=1e3, default=1e3),
    "max_sink_rate": Field(F, "m/s", "limit: relative vertical speed at contact", hi=100.0,
                           **_POS),
    "max_offset": Field(F, "m", "limit: horizontal distance from the pad centre",
                        hi=100.0, **_POS),
    "max_tilt_deg": Field(F, "deg", "limit: body z axis from the deck normal", hi=90.0, **_POS),
    "max_relative_speed": Field(F, "m/s", "limit: horizontal relative speed at contact",
                                hi=100.0, **_POS),
    "settle_time": Field(F, "s", "the run ends this long after touchdown", lo=0.0, hi=1e3),
    "max_gear_load": Field(F, "N", "limit: the gear's peak total normal load", hi=1e6, **_POS),
    "max_bounce": Field(F, "m", "limit: the lowest foot's rebound above the deck with "
                        "every foot off it", hi=100.0, **_POS),
    "pad_radius": Field(F, "m", "limit: the landing area's radius, which every foot "
                        "stays within from the first contact to the settle time", hi=100.0,
                        **_POS),
    "max_friction_margin": Field(F, "-", "secured without a lock: friction needed over "
                                 "available at rest, at the end, below this", hi=1.0,
                                 **_POS),
    "marker_timeout": Field(F, "s", "the descent starts only while the marker was seen "
                            "within this time", lo=0.0, hi=1e3),
    "search_height": Field(F, "m", "hover height while the marker is not seen (in align)",
                           hi=1e3, **_POS),
}
