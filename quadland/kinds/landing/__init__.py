"""The 6-DOF landing: its values, flight, report, linearization and flight code."""
