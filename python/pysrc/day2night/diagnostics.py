"""day2night's warnings as Python warning classes (docs/warnings.md).

Every warning the library raises is an instance of ``Day2NightWarning`` (a ``UserWarning``),
or rather of the subclass of its code: ``NoiseExtrapolatedWarning`` for the code
``noise-extrapolated``, and so on, one class per code of the Rust ``day2night::Code``
(``WARNING_CODES`` lists them with a one-line summary). Each class has the ``code``
attribute; each warning raised has ``code``, ``subject`` (the file, scene or option it is
about) and ``message`` (the text the command line prints after
``warning[CODE]: SUBJECT:``). Its ``str`` is ``"SUBJECT: MESSAGE"``.

>>> import warnings, day2night
>>> with warnings.catch_warnings(record=True) as got:
...     warnings.simplefilter("always")
...     day2night.synthesize(raw, seed=0, isos=(25,))
>>> [w.category.code for w in got]
['noise-extrapolated']
>>> warnings.simplefilter("ignore", day2night.NoiseExtrapolatedWarning)  # silence one code
"""

import sys as _sys
import warnings as _warnings

from ._native import WARNING_CODES

__all__ = ["Day2NightWarning", "WARNING_CLASSES", "WARNING_CODES", "warning_class"]


class Day2NightWarning(UserWarning):
    """A warning of day2night; its subclass per code has the ``code`` attribute."""

    code = None

    def __init__(self, message, subject=""):
        super().__init__(f"{subject}: {message}" if subject else message)
        self.subject = subject
        self.message = message


def _class_name(code):
    return "".join(part.capitalize() for part in code.split("-")) + "Warning"


#: The class of each code: ``{"noise-extrapolated": NoiseExtrapolatedWarning, ...}``.
WARNING_CLASSES = {}
for _code, _summary in WARNING_CODES:
    _name = _class_name(_code)
    _cls = type(
        _name,
        (Day2NightWarning,),
        {"code": _code, "__doc__": f"``{_code}``: {_summary}.", "__module__": __name__},
    )
    WARNING_CLASSES[_code] = _cls
    globals()[_name] = _cls
    __all__.append(_name)
del _code, _summary, _name, _cls


def warning_class(code):
    """The ``Day2NightWarning`` subclass of ``code`` (``Day2NightWarning`` itself for a code
    this version does not know)."""
    return WARNING_CLASSES.get(code, Day2NightWarning)


# Code of Python wrappers of native functions (signatures.py) that a warning passes through
# to the wrapper's caller.
PASS_THROUGH = set()


def _emit(code, subject, message, stacklevel):
    """Raise one warning of the extension (called from Rust, python/src/convert.rs)."""
    frame = _sys._getframe(stacklevel - 1)
    while frame is not None and frame.f_code in PASS_THROUGH:
        frame = frame.f_back
        stacklevel += 1
    _warnings.warn(warning_class(code)(message, subject), stacklevel=stacklevel)
