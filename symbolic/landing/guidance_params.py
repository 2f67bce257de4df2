"""The landing guidance's parameters: the ``[landing]`` keys of a landing scenario as the
flight code reads them (:mod:`quadland_symbolic.landing.guidance` steps on them; the
scenario's keys are checked by ``quadland.schema.guidance``)."""

from __future__ import annotations

from quadland_symbolic.layout import Field, Layout

__all__ = ["GUIDANCE_PARAMS"]

#: The guidance's parameters (the [landing] keys of a landing scenario).
GUIDANCE_PARAMS = Layout("p_guid", (
    Field("hover_height", 1, "m", "height of the hover point above the pad (centre)"),
    Field("align_radius", 1, "m", "distance to the hover point that ends the approach"),
    Field("dwell_time", 1, "s", "time the align criteria must hold"),
    Field("descent_speed", 1, "m/s", "largest descent rate"),
    Field("descent_time", 1, "s", "height over rate: the descent rate is h / descent_time"),
    Field("touchdown_speed", 1, "m/s", "descent rate at touchdown (the crawl)"),
    Field("touchdown_height", 1, "m", "the centre's height above the pad at contact"),
    Field("max_offset", 1, "m", "largest horizontal offset at touchdown"),
    Field("max_relative_speed", 1, "m/s", "largest horizontal relative speed at touchdown"),
    Field("max_deck_rise", 1, "m/s", "largest deck rise rate at which a descent goes on"),
    Field("settle_time", 1, "s", "time from touchdown to landed"),
    Field("marker_timeout", 1, "s", "largest marker age at which the align criteria count"),
    Field("search_height", 1, "m", "hover height while the marker is not seen (in align)"),
    Field("commit_height", 1, "m", "height above touchdown where the descent waits for a calm "
          "window"),
    Field("commit_horizon", 1, "s", "how far ahead the deck's rise must be predicted calm"),
    Field("calm_speed", 1, "m/s", "largest predicted vertical speed of the deck over the "
          "horizon at which the final descent commits"),
    Field("motion_time", 1, "s", "time constant of the deck motion's averages (quiescence)"),
    Field("fly_on", 1, "0/1", "1: the touchdown policy flies on until the lock holds "
          "(quadland_symbolic.landing.touchdown_policy); 0: its commands are inert"),
    Field("flare_height", 1, "m", "reference height above touchdown below which the tilt "
          "is limited to flare_tilt"),
    Field("flare_tilt", 1, "rad", "tilt limit of the thrust axis from the flare on"),
    Field("hold_time", 1, "s", "time from touchdown during which the flight code flies on"),
    Field("level_time", 1, "s", "time of the level-out and the thrust's ramp-down after it"),
    Field("cut_time", 1, "s", "time from touchdown to the cut (at least hold_time + level_time)"),
    Field("aim_height", 1, "m", "reference height above touchdown below which the aim point "
          "anticipates the level-out's pivot"),
    Field("pivot_x", 1, "m", "the pivot's arm along x the aim anticipates (0: none)"),
    Field("pivot_y", 1, "m", "the pivot's arm along y the aim anticipates (0: none)"),
    Field("pivot_h", 1, "m", "the pivot's height below the centre of mass (0: none)"),
    Field("descent_leash", 1, "m", "how far the falling reference may lead the quadrotor "
          "down (0: no limit)"),
    Field("leash_height", 1, "m", "reference height above touchdown below which the leash "
          "holds (above it the reference falls free)"),
    Field("withdraw_height", 1, "m", "reference height above touchdown at or below which a "
          "rising deck (or a swerve) no longer withdraws the committed descent (-1000: it "
          "does everywhere)"),
    Field("calm_tilt", 1, "rad", "largest angle, predicted at the contact, between the deck's "
          "normal and the flare's worst lean at which the final descent commits (pi: no "
          "limit)"),
    Field("contact_drop", 1, "m", "how much higher the centre meets the deck leaning than "
          "level (its lowest foot that much lower): the profile descends to "
          "touchdown_height + contact_drop (0: the level gear)"),
    Field("crawl_pause", 1, "0/1", "1: out of the align band the crawl pauses too, as the "
          "descent above it does; 0: the crawl is committed"),
    Field("swerve_accel", 1, "m/s^2", "the pad's horizontal acceleration above which the final "
          "descent does not commit and a committed one is withdrawn (0: no hold)"),
    Field("crawl_gate", 1, "m", "the crawl pauses while the horizontal offset predicted at "
          "the contact (estimate + velocity x time to contact) is farther than this from the "
          "pad (0: no gate)"),
    Field("crawl_gate_time", 1, "s", "longest time to contact crawl_gate's prediction spans"),
    Field("crawl_gate_floor", 1, "m", "reference height above touchdown at or below which "
          "crawl_gate no longer pauses the crawl (0: down to the touchdown height)"),
    Field("crawl_gate_wait", 1, "s", "longest time crawl_gate holds a crawl, then it falls on"),
    Field("crawl_gate_rise", 1, "m/s", "crawl_gate holds the crawl only while the deck's "
          "vertical speed at the pad is within this (a quiescent deck)"),
    Field("crawl_gate_wait_height", 1, "m", "reference height above touchdown at or below "
          "which crawl_gate_wait bounds the gate's holds (1000: everywhere)"),
    Field("calm_lean", 1, "rad", "largest lean of the body z axis from the vertical, "
          "averaged over lean_time, at which the final descent commits (pi/2: no limit)"),
    Field("lean_time", 1, "s", "time constant of the lean's average for calm_lean"),
    Field("lean_withdraw", 1, "0/1", "1: once committed, the lean's average past calm_lean "
          "withdraws the descent above withdraw_height, as a rising deck does; 0: it "
          "only holds the commit"),
    Field("abort_floor", 1, "m", "the gear's height above the deck, as estimated, at or "
          "below which the crawl's out-of-limits abort is not started (-1000: never)"),
    Field("ground_airmode", 1, "0/1", "1: from touchdown on the collective still rises for the "
          "moments, as in flight; 0: it does not (touchdown_policy)"),
    Field("flare_deck_tilt", 1, "rad", "flare: the thrust axis's limit from the deck's normal"),
    Field("flare_deck_height", 1, "m", "height above touchdown below which flare_deck_tilt holds"),
    Field("crawl_abort_offset", 1, "m", "the crawl's out-of-limits abort also past this "
          "horizontal offset, as estimated (1000: past max_offset only)"),
    Field("crawl_gate_count_height", 1, "m", "reference height above touchdown at or below "
          "which the gate's holds count toward crawl_gate_wait (1000: everywhere)"),
    Field("crawl_abort_budget", 1, "-", "crawl_abort_offset holds while the descent's "
          "abort count is below this, then max_offset alone (1e6: always)"),
    Field("withdraw_budget", 1, "-", "once the descent's abort count reaches this, nothing "
          "withdraws the committed crawl (1e6: always withdrawn, as above it)"),
), "landing guidance parameters")
