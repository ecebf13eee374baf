"""Exceptions that carry a message meant for the experimenter.

Each names the file, channel or key concerned, the problem and what would be accepted. The CLI
prints the message (no traceback) and exits with the class's ``exit_code``.
"""


class FsiLabError(Exception):
    """Base class of errors reported to the user without a traceback."""

    exit_code = 1


class ParameterError(FsiLabError, ValueError):
    """A parameter value is missing, unknown, of the wrong type or out of bounds."""

    exit_code = 2


class ProfileError(FsiLabError):
    """A profile cannot be used: syntax, unknown key, wrong type, bounds, unknown plugin."""

    exit_code = 2


class SafetyError(FsiLabError):
    """The requested excitation would exceed a safety limit of the profile."""

    exit_code = 2


class InputFileError(FsiLabError):
    """A CSV or run file given on the command line cannot be read."""

    exit_code = 2


class PluginError(FsiLabError):
    """A plugin is missing, failed to load, or broke its contract."""

    exit_code = 2


class InstrumentError(FsiLabError):
    """An instrument did not answer, answered wrongly, or reported a fault."""

    exit_code = 1


class AnalysisError(FsiLabError, ValueError):
    """An analysis cannot be carried out on the given signal (names plugin, channel, condition).

    A ``ValueError`` too, as scipy's signal functions raise for input they cannot use: a
    notebook that calls :mod:`fsi_lab.dsp` catches either."""

    exit_code = 1


class RunAborted(BaseException):
    """The run was stopped on request (Ctrl+C, SIGTERM, GUI abort).

    A BaseException, like KeyboardInterrupt, so that generic ``except Exception`` handlers in
    drivers do not swallow it.
    """
