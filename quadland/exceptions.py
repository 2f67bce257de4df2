"""Exceptions raised by quadland."""

__all__ = ["QuadlandError", "ScenarioError", "SingularAttitudeError", "CompilerNotFoundError",
           "OperatingPointError", "MarginsError"]


class QuadlandError(Exception):
    """Base class of the errors quadland reports as one line."""


class ScenarioError(QuadlandError, ValueError):
    """A scenario file or override is malformed or non-physical."""


class SingularAttitudeError(QuadlandError, ArithmeticError):
    """cos(theta) cos(phi) is too small to invert the thrust map."""


class CompilerNotFoundError(QuadlandError, RuntimeError):
    """No C compiler was found to build the generated code."""


class OperatingPointError(QuadlandError, ArithmeticError):
    """No operating point could be found or used for a linearization."""


class MarginsError(QuadlandError, ValueError):
    """A margins request is malformed (time, requirement or output folder)."""
