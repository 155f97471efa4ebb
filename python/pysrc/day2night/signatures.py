"""The signatures Python shows for the synthesis functions, made from the option table.

The native functions take the table's options (src/synth/options/table.rs) as keyword
arguments; their own parameters are declared once in Rust, where the call binds them
(``_native.PARAMETERS``) or in their text signature. Here both become an
``inspect.Signature``: the function's own parameters, then every option the function takes
as a keyword-only parameter with its default (``_native.KEYWORDS``), so
``inspect.signature(day2night.synthesize)``, ``help()`` and editors list them.
docs/python.md's option section is generated from these signatures
(python/tests/test_python_signatures.py).
"""

import functools
import inspect

from . import _native, diagnostics

P = inspect.Parameter

# Which keyword options each function takes (``_native.KEYWORDS``' scopes).
SCOPES = {
    "synthesize": "in_memory",
    "night_pair": "in_memory",
    "fresh_pair": "in_memory",
    "NightPairs": "in_memory",
    "write_unit": "files",
    "write_units": "files",
    "dataset_units": None,
}


def own_parameters(func):
    """The parameters ``func`` declares itself (not its keyword options)."""
    listed = _native.PARAMETERS.get(func.__name__)
    if listed is None:
        return [p for p in inspect.signature(func).parameters.values()
                if p.kind not in (P.VAR_POSITIONAL, P.VAR_KEYWORD)]
    return [P(name, getattr(P, kind), default=default if has_default else P.empty)
            for name, kind, has_default, default in listed]


def option_parameters(scope):
    """The keyword options of ``scope`` as keyword-only parameters, in the table's order."""
    if scope is None:
        return []
    return [P(name, P.KEYWORD_ONLY, default=default)
            for name, default in _native.KEYWORDS[scope]]


def signature(func, name=None):
    """``func``'s own parameters, then the keyword options it takes."""
    name = name or func.__name__
    own = own_parameters(func)
    taken = {p.name for p in own}
    options = [p for p in option_parameters(SCOPES[name]) if p.name not in taken]
    return inspect.Signature(own + options)


def signed(func):
    """``func`` (a native function) with the signature made from the table."""
    @functools.wraps(func)
    def call(*args, **kwargs):
        return func(*args, **kwargs)

    call.__signature__ = signature(func)
    call.__module__ = "day2night"
    # Its warnings are about the caller's line, as the native function's are.
    diagnostics.PASS_THROUGH.add(call.__code__)
    return call


def sign_class(cls):
    """``cls``'s ``__init__`` with its own parameters and the keyword options it takes
    (``**options`` replaced by them)."""
    init = cls.__init__
    own = [p for p in inspect.signature(init).parameters.values()
           if p.kind != P.VAR_KEYWORD]
    taken = {p.name for p in own}
    options = [p for p in option_parameters(SCOPES[cls.__name__]) if p.name not in taken]
    init.__signature__ = inspect.Signature(own + options)
    return cls
