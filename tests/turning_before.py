"""turning's touchdown and gains before issue 19's flare (``bf41d33``): the rotors cut at
the contact switch, the magnet 0.25 s after it, a 30 deg tilt limit, the outer bias
estimates on x and y and the observer off on z (docs/landing.md, "turning: the flare, and
the observer alone"), and the navigation filter's PX4 defaults for the accelerations'
noise (``q_acc``, ``q_at``; docs/landing.md, "turning: what the offset at contact is made
of"). The judge's tests that force turning's crawl into the roof pin
flights with the rotor cut at the switch; they fly these, on the pad of before: the large
marker alone (docs/landing.md, "The nested marker"), and the crawl and land detector of
before (``reference.TURNING_SEVENTEENTH``)."""

from reference import TURNING_SEVENTEENTH

BEFORE = ['touchdown.policy="idle"', "touchdown.flare_height=0.15",
          "touchdown.flare_tilt_deg=34.0", "touchdown.level_time=0.35",
          "touchdown.cut_time=0.5", "touchdown.lock_delay=0.25",
          "controller.tilt_max_deg=30.0", "controller.ki_p=[0.5, 0.5, 1.0]",
          "controller.observer_frequency=[12.0, 12.0, 0.0]",
          "estimator.q_acc=[0.02, 0.02, 0.02]", "estimator.q_at=[0.1, 0.1, 0.1]",
          "sensors.vision.small_range_max=0.0", *TURNING_SEVENTEENTH]
