"""The paper's 4-DOF loop: its values, flight, report, linearization and flight code."""

#: The scenario whose values the paper's half of ``generated/`` carries (here, not in
#: ``flight``, so that the kind names it without loading its flight code).
PAPER_SCENARIO = "paper"
