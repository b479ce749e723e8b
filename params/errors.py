"""The user-facing errors, and the integer tests every validator of the parameters shares."""

import numbers

__all__ = ["UserError", "ParameterError"]


class UserError(Exception):
    """Anything the user can fix: a bad parameter, a missing or malformed file, a missing tool.

    The message is one line naming what is wrong and what is allowed; the command line
    prints it as is and exits with code 2, without a traceback.
    """


class ParameterError(UserError, ValueError):
    """A parameter outside what the model and the hardware support.

    The message is one line naming the parameter, the offending value and what is allowed;
    the command line prints it as is and exits with code 2.
    """


def is_int(value):
    """A true integer: ``bool`` is an ``int`` subclass, but ``block=True`` is a mistake."""
    return isinstance(value, int) and not isinstance(value, bool)


def is_integral(value):
    """An integer of any kind (numpy's included: sweeps compute penalties with numpy), not
    a ``bool``."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)
