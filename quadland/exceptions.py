"""Exceptions raised by quadland."""

__all__ = ["QuadlandError", "ScenarioError", "SimulationError", "SingularAttitudeError",
           "CompilerNotFoundError", "CompileError", "CodegenError", "OperatingPointError",
           "MarginsError", "CampaignError", "CampaignStopped", "SettingError"]


class QuadlandError(Exception):
    """Base class of the errors quadland reports as one line."""


class ScenarioError(QuadlandError, ValueError):
    """A scenario file or override is malformed or non-physical."""


class SimulationError(QuadlandError, RuntimeError):
    """The simulated flight failed: singular attitude, a non-finite state or output.

    Attributes
    ----------
    time : float or None
        s, when it failed.
    partial : SimulationResult or None
        The trajectory up to the failure, when one was recorded.
    """

    def __init__(self, message: str, time: float | None = None, partial=None):
        super().__init__(message)
        self.time = time
        self.partial = partial


class SingularAttitudeError(QuadlandError, ArithmeticError):
    """cos(theta) cos(phi) is too small to invert the thrust map."""


class CompilerNotFoundError(QuadlandError, RuntimeError):
    """No C compiler was found to build the generated code."""


class CompileError(QuadlandError, RuntimeError):
    """The C compiler failed on generated sources."""


class SettingError(QuadlandError, ValueError):
    """An environment setting of quadland's (``QUADLAND_COMPILE_TIMEOUT``) is malformed."""


class CodegenError(QuadlandError, ValueError):
    """Generated code cannot be written where asked (no checkout, wrong scenario)."""


class OutputError(QuadlandError, OSError):
    """An output folder cannot be used (not a folder, in use, not writable)."""


class OperatingPointError(QuadlandError, ArithmeticError):
    """No operating point could be found or used for a linearization."""


class MarginsError(QuadlandError, ValueError):
    """A margins request is malformed (operating time or requirement)."""


class CampaignError(QuadlandError, ValueError):
    """A campaign cannot start or resume where asked (folder, scheduler, changed scenario)."""


class CampaignStopped(QuadlandError, RuntimeError):
    """A campaign stopped before its end (a worker or the scheduler was lost).

    The runs recorded so far are kept; running the same command again
    resumes it.
    """
