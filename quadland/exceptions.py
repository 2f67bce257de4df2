"""Exceptions raised by quadland."""

__all__ = ["QuadlandError", "ScenarioError", "SimulationError", "SingularAttitudeError",
           "CompilerNotFoundError", "CompileError", "CodegenError", "OperatingPointError",
           "MarginsError"]


class QuadlandError(Exception):
    """Base class of the errors quadland reports as one line."""


class ScenarioError(QuadlandError, ValueError):
    """A scenario file or override is malformed or non-physical."""


class SimulationError(QuadlandError, RuntimeError):
    """The simulated loop left the model's domain (singular attitude, NaN)."""


class SingularAttitudeError(QuadlandError, ArithmeticError):
    """cos(theta) cos(phi) is too small to invert the thrust map."""


class CompilerNotFoundError(QuadlandError, RuntimeError):
    """No C compiler was found to build the generated code."""


class CompileError(QuadlandError, RuntimeError):
    """The C compiler failed on generated sources."""


class CodegenError(QuadlandError, ValueError):
    """Generated code cannot be written where asked (no checkout, wrong scenario)."""


class OperatingPointError(QuadlandError, ArithmeticError):
    """No operating point could be found or used for a linearization."""


class MarginsError(QuadlandError, ValueError):
    """A margins request is malformed (time, requirement or output folder)."""
