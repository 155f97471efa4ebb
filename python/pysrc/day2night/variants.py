"""The experiment's and the trainer's variants, each named once: the protocol, the ISP of the
targets, the noise of the synthetic noisy inputs, how their ISO is chosen, the layout of the
captures a real set was made from, and the geometry of a target. Code compares with these members, never with the
literal names (python/tests/test_variants.py holds it).

A member is its name as a string (``class X(str, Enum)``: ``enum.StrEnum`` is Python 3.11+,
the package supports 3.9): equal to it and hashed as it (a dict key, a set member, a
command-line choice, a JSON value), printed, formatted and shown in a signature as it, so
``Isp.RELEASE == "release"`` and ``f"{Isp.RELEASE}" == "release"``."""

import enum

__all__ = ["Variant", "Protocol", "Isp", "Noise", "SynthIso", "Layout", "Geometry"]


class Variant(str, enum.Enum):
    """A named variant: a string that is one of its class's names."""

    def __str__(self):
        return self.value

    def __repr__(self):
        return repr(self.value)

    def __format__(self, spec):
        return format(self.value, spec)


class Protocol(Variant):
    """``--protocol``: day2night's options, or the release's (experiment/protocol.py)."""

    DAY2NIGHT = "day2night"
    RELEASE = "release"


class Isp(Variant):
    """The ISP of a target (``--targets``, ``render_target(isp=...)``): the authors'
    release's, or day2night's software ISP."""

    RELEASE = "release"
    DAY2NIGHT = "day2night"


class Noise(Variant):
    """``--noise``: the synthesis' own noise model, or the release's S20 FE table
    (experiment/release_noise.py)."""

    DAY2NIGHT = "day2night"
    RELEASE = "release"


class SynthIso(Variant):
    """``--synth-iso``: alternate the noisy ISOs by slot, or draw one per day image as the
    release does."""

    ALTERNATE = "alternate"
    RELEASE = "release"


class Layout(Variant):
    """The layout of a capture folder ``day2night real-pairs`` read (its scene record's
    ``layout``): the release's ``RAW_0_00...`` names, or a simple folder of DNGs."""

    RELEASE = "release"
    SIMPLE = "simple"


class Geometry(Variant):
    """How a target sits on the pixel grid (experiment/pairs.py ``align``): the active area
    as stored, day2night's render (DefaultCrop, Orientation), or the release's render."""

    RAW = "raw"
    RENDER = "render"
    RELEASE = "release"
