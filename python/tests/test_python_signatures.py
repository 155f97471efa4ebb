"""The synthesis functions' signatures against the option table, and docs/python.md's option
section against the signatures.

docs/python.md's block between ``<!-- synth-options`` and ``<!-- /synth-options -->`` is
generated here from ``inspect.signature`` of each function (the metrics' too) and the table
(``_native.SYNTH_OPTIONS``): ``D2N_BLESS=1 python -m pytest python/tests/test_python_signatures.py``
rewrites it; without that the test fails when the two differ. Each row of the table is then
exercised: its option accepted with a valid value other than its default, and refused when
out of its range or choices, with an error naming the option.
"""

import inspect
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import day2night
from day2night import _native, signatures

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "python.md"
TABLE = _native.SYNTH_OPTIONS
P = inspect.Parameter

# The functions that take the table's options, by the columns of the generated table.
FUNCTIONS = {
    "synthesize": day2night.synthesize,
    "night_pair": day2night.night_pair,
    "NightPairs": day2night.NightPairs,
    "write_unit": day2night.write_unit,
    "write_units": day2night.write_units,
}
# The metrics, whose signatures the block lists too (docs/python.md, "Metrics").
METRICS = ("psnr", "ssim", "delta_e2000", "delta_e2000_map")
# A parameter of its own that is a table option under another name (a sequence of them).
SPELLED = {"isos": "iso"}
START = "<!-- synth-options:"
END = "<!-- /synth-options -->\n"


def params(func):
    return inspect.signature(func).parameters


def option_of(name, func_name):
    """The table's option a parameter called ``name`` of ``func_name`` is, or None (an
    in-memory function's own ``target`` is not the table's file target)."""
    key = SPELLED.get(name, name)
    e = TABLE.get(key)
    if e is None or e["python"] == "files" and signatures.SCOPES[func_name] != "files":
        return None
    return key


# What an own parameter named like a table option it is not takes.
OWN = {("synthesize", "target"): '`"linear"` (the float32 linear target) or None'}


def homonyms():
    """Own parameters named like a table option that they are not."""
    out = []
    for name, func in FUNCTIONS.items():
        for n in params(func):
            if n in TABLE and option_of(n, name) is None:
                out.append(f"`{name}`'s own `{n}` is not the table's `{n}`: it takes "
                           f"{OWN[(name, n)]}.")
    return out


def value_text(key):
    e = TABLE[key]
    kind = e["kind"]
    if kind == "switch":
        return "bool"
    if kind == "int":
        lo, hi = e["range"]
        return f"int, {lo}..={hi}"
    if kind == "float":
        return "number"
    if kind == "choice":
        return ", ".join(f'`"{c}"`' for c in e["choices"])
    if kind == "isos":
        return 'ISOs: a sequence of ints (`isos`), one int (`iso`), or `"800,3200"`/`"none"` text'
    if kind == "numbers":
        n = e["value_name"].count(",") + 1
        return f'{n} numbers (a sequence, or `"{e["value_name"].lower()}"` text)'
    if kind == "path":
        return "path"
    return f"str: {e['help']}"


def cell(func_name, key):
    """How ``func_name`` takes the option ``key``: its parameter name, or a dash."""
    for name, p in params(FUNCTIONS[func_name]).items():
        if option_of(name, func_name) == key:
            how = [] if p.kind == P.KEYWORD_ONLY else ["parameter"]
            how += ["required"] if p.default is P.empty else []
            return f"`{name}`" + (f" ({', '.join(how)})" if how else "")
    return "—"


def signature_line(name, func):
    """The signature with the keyword options it takes shown as one placeholder."""
    scope = signatures.SCOPES[name]
    options = {k for k, _ in _native.KEYWORDS[scope]} if scope else set()
    own = [p for p in params(func).values() if not (p.kind == P.KEYWORD_ONLY and p.name in options)]
    text = str(inspect.Signature(own))[1:-1]
    if options:
        placeholder = {"in_memory": "**in-memory options", "files": "**file options"}[scope]
        text += (", " if "*" in text.split(", ") else ", *, ") + placeholder
    return f"- `{name}({text})`"


def block():
    """docs/python.md's generated block."""
    lines = [
        f"{START} generated from inspect.signature and the option table by "
        "python/tests/test_python_signatures.py; D2N_BLESS=1 python -m pytest "
        "python/tests/test_python_signatures.py rewrites it -->",
        "Signatures (`inspect.signature`; `**in-memory options` are the table's options the "
        "`synthesize` column marks, `**file options` those of `write_unit`, each keyword-only "
        "with its default):",
        "",
    ]
    for name, func in FUNCTIONS.items():
        lines.append(signature_line(name, func))
    lines.append(signature_line("dataset_units", day2night.dataset_units))
    lines += ["", "The metrics (`day2night eval`'s numbers, and the per-pixel map behind its "
              "Delta E; no table options):", ""]
    for name in METRICS:
        lines.append(f"- `{name}{inspect.signature(getattr(day2night, name))}`")
    lines += [
        "",
        *homonyms(),
        "",
        "| Keyword | Flag | Value | Default | `synthesize` | `night_pair` | `NightPairs` "
        "| `write_unit`, `write_units` |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, e in TABLE.items():
        kw = f"`{key}`" + (f" (or `{e['alias']}`)" if e["alias"] else "")
        cells = [cell(f, key) for f in ("synthesize", "night_pair", "NightPairs",
                                                   "write_unit")]
        lines.append(f"| {kw} | `{e['flag']}` | {value_text(key)} | "
                     f"`{e['python_default']!r}` | " + " | ".join(cells) + " |")
    lines.append("")
    for key, e in TABLE.items():
        if e["python"] == "absent":
            lines.append(f"- `{key}` is not a keyword option: {e['note']}.")
    lines += [
        "",
        'Not options (the same in every run; docs/synthesis.md, "Options and constants"):',
        "",
        "| Sidecar field | Value | Why |",
        "|---|---|---|",
    ]
    for field, value, why in _native.SYNTH_CONSTANTS:
        lines.append(f"| `{field}` | {value} | {why} |")
    return "\n".join(lines) + "\n" + END


def test_docs_are_the_signatures():
    doc = DOC.read_text()
    start = doc.index(START)
    end = doc.index(END, start) + len(END)
    want = block()
    if doc[start:end] != want:
        if os.environ.get("D2N_BLESS"):
            DOC.write_text(doc[:start] + want + doc[end:])
        else:
            pytest.fail("docs/python.md's option section differs from the signatures: run "
                        "D2N_BLESS=1 python -m pytest python/tests/test_python_signatures.py")


@pytest.mark.parametrize("name", FUNCTIONS)
def test_signatures_list_the_table(name):
    """Every option a function takes is in its signature with the table's default, once."""
    func = FUNCTIONS[name]
    scope = signatures.SCOPES[name]
    ps = params(func)
    assert not any(p.kind == P.VAR_KEYWORD for p in ps.values()), name
    for key, e in TABLE.items():
        spelled = [n for n in ps if option_of(n, name) == key]
        if e["python"] == "absent" and key != "seed":
            assert not spelled, (name, key)
            continue
        takes = (e["python"] == "keyword" or scope == "files" and e["python"] != "absent")
        if takes:
            assert spelled, f"{name} does not list {key}"
        for n in spelled:
            d = ps[n].default
            if d is P.empty or e["kind"] == "isos" and n == "iso" and scope != "files":
                continue
            assert d == e["python_default"], (name, n, d, e["python_default"])


def test_own_parameters_have_the_table_defaults():
    """A function's own parameter that is a table option has the option's default
    (NightPairs' are written in pairs.py, night_pair's in its Rust signature)."""
    for name, func in [*FUNCTIONS.items(), ("dataset_units", day2night.dataset_units)]:
        for n, p in params(func).items():
            key = option_of(n, name if name in FUNCTIONS else "write_unit")
            if key and p.default is not P.empty:
                assert p.default == TABLE[key]["python_default"], (name, n)


@pytest.fixture(scope="module")
def raw(day_dng):
    return day2night.read_dng(day_dng)


CROP = (0, 0, 32, 32)


def small(raw, **kw):
    return day2night.synthesize(raw, isos=(1600,), crop=CROP, **kw)


def test_the_shown_defaults_are_the_defaults(raw):
    """Passing every default the signature shows gives what passing none gives."""
    shown = {n: p.default for n, p in params(day2night.synthesize).items()
             if p.default is not P.empty and n not in ("isos", "crop")}
    a = small(raw, **shown)
    b = small(raw)
    for k in ("clean", "target"):
        assert np.array_equal(a[k], b[k]), k
    assert np.array_equal(a["noisy"][1600], b["noisy"][1600])
    assert a["plan"] == b["plan"]
    pair = {n: p.default for n, p in params(day2night.night_pair).items()
            if p.default is not P.empty}
    x = day2night.night_pair(raw, 0, 0, 1600, CROP, **pair)
    y = day2night.night_pair(raw, 0, 0, 1600, CROP)
    assert all(np.array_equal(x[k], y[k]) for k in ("noisy", "clean", "target"))


@pytest.fixture(scope="module")
def files(cli, day_dng, tmp_path_factory):
    """Calibration files for the path options."""
    d = tmp_path_factory.mktemp("calib")
    cli("calibrate", "brightness", day_dng, "-o", d / "brightness.json")
    return {
        "illuminants": "cie",
        "brightness": str(d / "brightness.json"),
        "noise_model": str(ROOT / "calibration" / "samsung-s20fe" / "noise.json"),
    }


# Valid values other than the default, and values refused, of the options whose kind does
# not give them (numbers, texts, paths); with the other options they need.
NEEDS = {"motion": {"burst": 2}, "shake_step": {"burst": 2}, "shake_roll": {"burst": 2},
         "warp_interp": {"burst": 2}}
VALID = {"ambient_gain": 0.1, "bulb_gain": (60, 80), "dim_range": (0.3, 0.5),
         "day_neutral": (0.5, 1.0, 0.6), "mask_eval": "truncated:3", "opcodes": "ignore",
         "motion": "none", "shake_step": 0.3, "shake_roll": 0.01, "warp_interp": "bilinear",
         "exr_compression": "piz", "iso": "800", "noise_gain": 2.0}
INVALID = {"ambient_gain": -1.0, "bulb_gain": (100, 50), "dim_range": (0.9, 0.5),
           "day_neutral": (1, 2), "mask_eval": "fast", "opcodes": "sometimes",
           "motion": "walk", "shake_step": -1.0, "shake_roll": float("nan"),
           "warp_interp": "nearest", "exr_compression": "jpeg", "iso": "0",
           "illuminants": "nowhere.json", "brightness": "nowhere.json",
           "noise_model": "nowhere.json", "noise_gain": 0.0}
# What an error of each says when it is not the keyword (the options checked together).
NAMED = {"illuminants": "nowhere.json", "brightness": "nowhere.json",
         "noise_model": "nowhere.json", "shake_step": "shake", "shake_roll": "shake",
         "iso": "ISO"}


def samples(key, files):
    """(valid, invalid) values of the option ``key``."""
    e = TABLE[key]
    kind = e["kind"]
    if kind == "switch":
        return True, "yes"
    if kind == "int":
        lo, hi = e["range"]
        default = e["python_default"]
        return (hi if default != hi else lo), hi + 1
    if kind == "choice":
        other = [c for c in e["choices"] if c != e["python_default"]]
        return other[0], "bogus"
    if kind == "path":
        return files[key], INVALID[key]
    return VALID[key], INVALID[key]


ROWS = [k for k, e in TABLE.items() if e["python"] != "absent"]


@pytest.mark.parametrize("key", ROWS)
def test_each_row_is_taken_and_checked(raw, files, day_dng, tmp_path, key):
    e = TABLE[key]
    good, bad = samples(key, files)
    extra = dict(NEEDS.get(key, {}))
    if key == "compat":
        extra["mask_eval"] = "release"
    if e["python"] == "keyword":
        call = lambda v: small(raw, target=None, **extra, **{key: v})  # noqa: E731
    else:
        days = tmp_path / "days"
        days.mkdir()
        shutil.copy(day_dng, days / "day.dng")
        unit = day2night.dataset_units(days)[0]
        call = lambda v: day2night.write_unit(  # noqa: E731
            unit, tmp_path / "out", overwrite=True, **extra, **{key: v})
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        call(good)
        with pytest.raises((TypeError, ValueError, OSError)) as err:
            call(bad)
    msg = str(err.value)
    assert key in msg or NAMED.get(key, key) in msg, msg
