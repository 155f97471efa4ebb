"""The experiment's protocol options: which ISP renders the targets, which noise the synthetic
noisy inputs get, how their ISO is chosen, and whose fold lists split the real scenes.

``--protocol day2night`` (the default) and ``--protocol release`` are presets; each option is
also a flag of its own, and a flag given explicitly wins over the preset:

==================  ===========================  =================================
option              day2night                    release
==================  ===========================  =================================
``--targets``       the ISP of the real targets  ``release``
``--noise``         ``day2night``                ``release`` (release_noise.py)
``--synth-iso``     ``alternate``                ``release``
``--folds-file``    none (seeded folds)          required: the release's lists
==================  ===========================  =================================

``--targets`` defaults to the ISP that made the real set's targets: ``release`` when
``day2night real-pairs`` copied the release's PNGs (the processed ``night_real/`` tree) or
rendered them with ``--isp release``, else ``day2night``."""

import dataclasses
import json
import pathlib

import numpy as np

import day2night

from ..isos import NOISY_ISOS  # noqa: F401  (re-exported)
from ..variants import Isp, Noise, Protocol, SynthIso
from . import mix as mix_mod
from . import release_folds
from .folds import FoldError

TARGETS = tuple(Isp)
NOISE = tuple(Noise)
SYNTH_ISO = tuple(SynthIso)
PROTOCOLS = tuple(Protocol)


class ProtocolError(ValueError):
    """Protocol options that cannot be combined (the message names the flags)."""


#: Where an option the command line left out gets its value: the sources a field of
#: config.ExperimentConfig names in its ``default_from`` metadata (the preset's source,
#: presets.FROM_PRESET, is the fourth). :func:`for_run` gives the values of these three.
FROM_PROTOCOL, FROM_REAL_SET, FROM_FOLD_FILE = "protocol", "real set", "fold file"
#: The values each ``--protocol`` gives (the table above); under day2night's, ``--targets``
#: comes from the real set (:func:`real_target_isp`).
PRESETS = {Protocol.DAY2NIGHT: {"noise": Noise.DAY2NIGHT, "synth_iso": SynthIso.ALTERNATE},
           Protocol.RELEASE: {"targets": Isp.RELEASE, "noise": Noise.RELEASE,
                              "synth_iso": SynthIso.RELEASE}}


def _choice(value, choices, flag):
    if value is not None and value not in choices:
        raise ProtocolError(f"{flag} {value!r}: use {' or '.join(choices)}")
    return value


def check_flags(protocol=None, targets=None, noise=None, synth_iso=None, folds_file=None):
    """The flags as given (None: not given) checked: each a choice of its own, and
    ``--protocol release`` with a fold file."""
    _choice(protocol, PROTOCOLS, "--protocol")
    _choice(targets, TARGETS, "--targets")
    _choice(noise, NOISE, "--noise")
    _choice(synth_iso, SYNTH_ISO, "--synth-iso")
    if protocol == Protocol.RELEASE and folds_file is None:
        raise ProtocolError(
            "--protocol release needs --folds-file PATH: the release's "
            "utils/k_fold_indices_saved.p (or its JSON export; docs/experiment.md)"
        )


def fold_file(folds_file):
    """(absolute path, SHA-256, number of folds) of the fold file ``folds_file`` ((None,
    None, None) without one): read once (capped, a regular file only), parsed, and those
    same bytes hashed (release_folds.read_release_file)."""
    sha = count = None
    if folds_file is not None:
        # read once (capped, a regular file only), parsed, and those bytes hashed
        path = pathlib.Path(folds_file)
        try:
            lists, sha = release_folds.read_release_file(path)
        except FoldError as e:
            raise ProtocolError(str(e)) from None
        count = len(lists["test_index_all"])
        folds_file = str(path.resolve())
    return folds_file, sha, count


def _json_lines(path):
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return []
    out = []
    for line in text.splitlines():
        try:
            out.append(json.loads(line))
        except ValueError:
            continue  # realset.read_real reports a damaged manifest; here it counts for nothing
    return out


def scene_target_isp(root, rec):
    """``"release"`` or ``"day2night"``: the ISP of one real-pairs record's target PNG."""
    stages = [str(st) for st in rec.get("stages") or []]
    if "copy_target_png" in stages:
        return Isp.RELEASE  # the processed night_real tree's clean/NNN.png, copied
    if any(st.startswith("render_png") and Isp.RELEASE in st for st in stages):
        return Isp.RELEASE  # real-pairs --isp release, if its stage says so
    meta = pathlib.Path(root) / "real" / "meta" / f"{rec.get('scene')}.json"
    try:
        target = json.loads(meta.read_text(encoding="utf-8")).get("target") or {}
    except (OSError, ValueError, AttributeError):
        target = {}
    if target.get("png") == "copied" or target.get("isp") == Isp.RELEASE:
        return Isp.RELEASE
    return Isp.DAY2NIGHT


def real_target_isps(real_dir):
    """{scene id: "release" | "day2night"} of a real-pairs output folder (scenes whose record
    is not ``ok`` are left out; realset.read_real reports them)."""
    root = pathlib.Path(real_dir)
    out = {}
    for rec in _json_lines(root / "manifest.jsonl"):
        if not isinstance(rec, dict):
            continue  # realset.read_real refuses it, naming the file and the line
        if rec.get("kind", "real") == "real" and rec.get("status") == "ok" and rec.get("scene"):
            out[str(rec["scene"])] = scene_target_isp(root, rec)
    return out


def real_target_isp(real_dir):
    """The default of ``--targets``: ``release`` when every real target came from the release's
    ISP, else ``day2night``."""
    isps = set(real_target_isps(real_dir).values())
    return Isp.RELEASE if isps == {Isp.RELEASE} else Isp.DAY2NIGHT


def release_isos(names, seed, isos=NOISY_ISOS):
    """{day image: ISO} drawn as the release's prepare_data.py draws them: one ISO per image,
    uniformly from the list (``iso_list[np.random.randint(2)]``), over the sorted images
    (training and validation). The release's draws come from numpy's unseeded global stream
    between its synthesis draws, so only the rule is reproduced; here the draws are
    ``RandomState(seed).randint(len(isos), size=n)`` (deterministic)."""
    names = sorted(str(n) for n in names)
    draws = np.random.RandomState(seed).randint(len(isos), size=len(names))
    return {n: int(isos[int(k)]) for n, k in zip(names, draws)}


def with_isos(slots, isos):
    """``slots`` (mix.py's dicts) with each synthetic slot's ISO replaced by ``isos[id]``
    (``isos`` None: unchanged)."""
    if isos is None:
        return slots
    out = []
    for s in slots:
        s = dict(s)
        if s["kind"] == "synthetic":
            s["iso"] = isos[s["id"]]
        out.append(s)
    return out


# What a config.json written before these options ran with (resume reads a missing key as
# this): day2night's protocol, targets, noise and alternating ISOs, no fold file.
LEGACY_CONFIG = {"protocol": Protocol.DAY2NIGHT, "targets": Isp.DAY2NIGHT,
                 "noise": Noise.DAY2NIGHT, "synth_iso": SynthIso.ALTERNATE, "folds_file": None,
                 "folds_sha256": None}


def for_run(config):
    """What the protocol settles for ``config`` (config.ExperimentConfig, checked): returns
    (``config`` with its fold file absolute and hashed, {scene: ISP of its real target}, the
    values of the sources of its options left out: the protocol's preset, the real set's
    target ISP, the fold file's number of folds). A ``--folds`` that differs from the fold
    file's is an error."""
    isps = real_target_isps(config.real)
    real = Isp.RELEASE if isps and set(isps.values()) == {Isp.RELEASE} else Isp.DAY2NIGHT
    path, sha, count = fold_file(config.folds_file)
    counted = {}
    if path is not None:
        if config.folds is not None and int(config.folds) != count:
            raise ProtocolError(f"--folds {config.folds}: the fold file {path} holds {count} "
                                "folds (leave --folds out)")
        counted = {"folds": count}
    sources = {FROM_PROTOCOL: PRESETS[config.protocol], FROM_REAL_SET: {"targets": real},
               FROM_FOLD_FILE: counted}
    return dataclasses.replace(config, folds_file=path, folds_sha256=sha), isps, sources


def run_isos(synth_iso, days, seed):
    """{day image: ISO} of the run's synthetic noisy inputs under ``synth_iso = release``
    (``days``: the day images' names), else None (mix.py's alternation by slot)."""
    if synth_iso != SynthIso.RELEASE:
        return None
    return release_isos(days, seed)


def synthetic_slots(names, isos):
    """mix.synthetic_slots of ``names`` with the run's synthetic ISOs (:func:`run_isos`)."""
    return with_isos(mix_mod.synthetic_slots(names), isos)


def mixes_with_isos(mixes, isos):
    """``mixes`` (row: [slots per fold]) with the synthetic slots' ISOs replaced by the
    release's draw ``isos`` (None or empty: unchanged)."""
    if not isos:
        return mixes
    return {r: [with_isos(m, isos) for m in ms] for r, ms in mixes.items()}


def fresh_rows(selected, targets, noise, named):
    """The rows to run under the resolved ``targets`` and ``noise``. The fresh row
    synthesizes with day2night's ISP and noise (``FreshPatches`` has no release option), so
    under ``--targets release`` or ``--noise release`` it would put a second ISP into the
    table: it is left out of the default rows then, and refused when named."""
    if targets == Isp.DAY2NIGHT and noise == Noise.DAY2NIGHT:
        return selected
    if named and any(r.source == "fresh" for r in selected):
        raise ProtocolError(
            "--rows fresh: the fresh row synthesizes with day2night's ISP and noise, and this "
            f"run has --targets {targets} --noise {noise}: drop it from --rows, "
            "or pass --targets day2night --noise day2night")
    return [r for r in selected if r.source != "fresh"]


def notes(config, days, scenes, target_isps):
    """Lines for the run's log about what the protocol does not reach (``days``: {name:
    day DNG}; ``scenes``: the real scenes' ids)."""
    out = []
    if config.targets != Isp.DAY2NIGHT or config.noise != Noise.DAY2NIGHT:
        out.append("the fresh row is left out: it synthesizes with day2night's ISP and noise "
                   "(FreshPatches), and this run's targets or noise are the release's")
    if config.noise == Noise.RELEASE and days:
        first = sorted(days)[0]
        white = day2night.read_dng(str(days[first])).meta.get("white_level")
        if white is not None and float(white) != 1023:
            out.append(f"--noise release clips the noisy raws at 1023, as the release does for "
                       f"its 10-bit phone; {first} has white level {white:g}: its highlights "
                       "saturate")
    isps = [target_isps.get(s, Isp.DAY2NIGHT) for s in scenes]
    mixed = set(isps) - {config.targets}
    if mixed:
        n = sum(i != config.targets for i in isps)
        out.append(f"{n} real target(s) came from the {'/'.join(sorted(mixed))} ISP: rendered "
                   f"again from their clean raws by the {config.targets} ISP")
    return out
