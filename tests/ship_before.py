"""The ships' touchdown and horizontal integral action before their flare (docs/landing.md,
"The ships' flare"): main at c6b13f9, the keys that change moved, to the bit (and the
descent's leash, which ``ship`` took in its crawl after them: docs/landing.md, "The ships on
a leash in the crawl")."""

#: The thirteen keys, as they were.
NO_FLARE = ['touchdown.policy="idle"', "touchdown.flare_height=0.15",
            "touchdown.flare_tilt_deg=34.0", "touchdown.level_time=0.35",
            "touchdown.cut_time=0.5", "touchdown.lock_delay=0.25",
            "controller.tilt_max_deg=30.0", "controller.ki_p=[0.5, 0.5, 1.0]",
            "controller.observer_frequency=[0.0, 0.0, 0.0]",
            "controller.k1p=[1.5, 1.5, 3.0]", "controller.k2p=[1.5, 1.5, 3.0]",
            "landing.descent_leash=0.0", "landing.leash_height=1000.0"]

#: The pad of before: the large marker alone. ``ship_ss5`` nests the 0.1 m marker since the
#: eleventh session (docs/landing.md, "The nested marker on highway_100 and ship_ss5");
#: ``ship`` has none, so the key leaves its flights as they are.
PAD_BEFORE = "sensors.vision.small_range_max=0.0"

#: The datalink's gates of before: the 99 % of three degrees of freedom. ``ship_ss5`` gates its
#: broadcast at 30 since the thirteenth session (docs/landing.md, "ship_ss5: the datalink
#: refused at the deck's turn"); ``ship`` keeps these, so they leave its flights as they are.
GATES_BEFORE = ("estimator.gate_datalink_v=11.344867", "estimator.gate_datalink_a=11.344867")

#: The commit of before the thirteenth session, and the fourteenth's lean keys off:
#: ``ship_ss5`` since withdraws nothing in the crawl and waits for the deck's tilt at the
#: contact (docs/landing.md, "ship_ss5: the deck's roll at the contact and the withdrawals
#: in the crawl"); ``ship`` takes the defaults, so the keys leave its flights as they are;
#: and the withdrawals of before the twenty-first session, down to the contact however many:
#: ``ship`` keeps its crawl committed after three aborts since (docs/landing.md, "The ships'
#: repeated withdrawals"), which moves the rows with three aborts or more.
COMMIT_BEFORE = ["landing.withdraw_height=-1000.0", "landing.calm_tilt_deg=180.0",
                 "landing.calm_lean_deg=90.0", "landing.lean_withdraw=false",
                 "landing.withdraw_budget=1000000.0"]

#: The crawl's abort of before, down to the contact: ``ship_ss5`` starts none with its gear
#: within 6 cm of the deck since the fifteenth session (docs/landing.md, "ship_ss5: an abort
#: the gear cannot fly"); ``ship`` takes the default, so the key leaves its flights as they are.
ABORT_BEFORE = "landing.abort_floor=-1000.0"

#: The pad's heave of before: the random walk's constant acceleration in the filter and over
#: its horizon. ``ship_ss5`` carries it as the oscillator at 1.41 rad/s within its crawl since
#: the sixteenth session (docs/landing.md, "ship_ss5: the heave oscillator in the crawl
#: only"), ``ship`` at its sea state 4's 1.49 rad/s since the eighteenth (docs/landing.md,
#: "ship: the heave oscillator in the crawl at sea state 4's frequency").
HEAVE_BEFORE = ("estimator.heave_frequency=0.0", "estimator.heave_in_filter=0.0",
                "estimator.heave_height=1000000.0")

#: The flare of before about the vertical alone. ``ship_ss5`` also holds the thrust axis within
#: 16 deg of the deck's normal from the flare on since the seventeenth session (docs/landing.md,
#: "The ships' tilt at the contact: the flare held about the deck's normal too"); ``ship`` takes
#: the default (no limit), so the key leaves its flights as they are.
DECK_TILT_BEFORE = "touchdown.flare_deck_tilt_deg=90.0"

#: The crawl of before on ``ship_ss5``: the reference falls at the crawl's rate, on no leash.
#: ``ship_ss5`` flies ``ship``'s 2 cm leash in its crawl since the nineteenth session
#: (docs/landing.md, "ship_ss5: the crawl on the leash, with the heave in the filter");
#: ``ship`` has flown it since the tenth, so these keys are not its flights of before.
LEASH_BEFORE = ("landing.descent_leash=0.0", "landing.leash_height=1000.0")
