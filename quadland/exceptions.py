"""Exceptions raised by quadland."""

__all__ = ["QuadlandError", "ScenarioError", "SingularAttitudeError", "CompilerNotFoundError"]


class QuadlandError(Exception):
    """Base class of the errors quadland reports as one line."""


class ScenarioError(QuadlandError, ValueError):
    """A scenario file or override is malformed or non-physical."""


class SingularAttitudeError(QuadlandError, ArithmeticError):
    """cos(theta) cos(phi) is too small to invert the thrust map."""


class CompilerNotFoundError(QuadlandError, RuntimeError):
    """No C compiler was found to build the generated code."""
