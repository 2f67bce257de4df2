"""The paper's 4-DOF loop: its values, flight, report, linearization and flight code."""
