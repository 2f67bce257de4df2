"""The coupled 6-DOF landing plant: quadrotor, moving deck, relative state.

The paper's closing "further work": the 6-DOF quadrotor in E with motor lag
(:mod:`~quadland_symbolic.landing.quadrotor`), the surface vehicle of eq. (4) carrying
a deck with prescribed heave, roll and pitch (:mod:`~quadland_symbolic.landing.deck`),
the relative state in the deck frame (:mod:`~quadland_symbolic.landing.relative`) and
the whole as one ODE (:mod:`~quadland_symbolic.landing.plant`). See docs/landing.md.
"""
