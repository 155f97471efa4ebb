"""python/pysrc never unpickles (issue 42): no ``pickle.load``/``loads``, no ``Unpickler``,
no ``torch.load`` without ``weights_only=True``, no ``np.load(..., allow_pickle=True)`` and
no module that unpickles under another name (dill, cloudpickle, joblib, shelve, marshal).
The check reads the code's tokens (strings and comments, which may name these, are skipped)."""

import io
import pathlib
import tokenize

from conftest import ROOT

PICKLE_MODULES = {"pickle", "_pickle", "cPickle"}
LOADERS = {"load", "loads", "Unpickler"}
OTHER_MODULES = {"dill", "cloudpickle", "joblib", "shelve", "marshal"}


def _code_tokens(text):
    skip = {tokenize.COMMENT, tokenize.STRING, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT,
            tokenize.DEDENT, tokenize.ENCODING, tokenize.ENDMARKER}
    return [t for t in tokenize.generate_tokens(io.StringIO(text).readline)
            if t.type not in skip and not getattr(tokenize, "FSTRING_MIDDLE", -1) == t.type]


def _call_args(toks, i):
    """The tokens inside the call whose ``(`` is ``toks[i]``."""
    depth, j = 0, i
    while j < len(toks):
        depth += {"(": 1, ")": -1}.get(toks[j].string, 0)
        if depth == 0:
            return toks[i + 1:j]
        j += 1
    return toks[i + 1:]


def _has_kw(args, name, value):
    return any(a.string == name and b.string == "=" and c.string == value
               for a, b, c in zip(args, args[1:], args[2:]))


def violations(text):
    """(line, what) of every unpickling call or import in Python source ``text``."""
    toks, out = _code_tokens(text), []
    for i, t in enumerate(toks):
        nxt = [u.string for u in toks[i + 1:i + 4]]
        if t.string == "Unpickler":
            out.append((t.start[0], "Unpickler"))
        elif t.string in PICKLE_MODULES and nxt[:1] == ["."] and nxt[1:2] and nxt[1] in LOADERS:
            out.append((t.start[0], f"{t.string}.{nxt[1]}"))
        elif t.string == "from" and nxt[:1] and nxt[0] in PICKLE_MODULES:
            out.append((t.start[0], f"from {nxt[0]} import"))
        elif t.string in OTHER_MODULES:
            out.append((t.start[0], f"the module {t.string}"))
        elif t.string == "torch" and nxt[:3] == [".", "load", "("]:
            if not _has_kw(_call_args(toks, i + 3), "weights_only", "True"):
                out.append((t.start[0], "torch.load without weights_only=True"))
        elif t.string in ("np", "numpy") and nxt[:3] == [".", "load", "("]:
            if _has_kw(_call_args(toks, i + 3), "allow_pickle", "True"):
                out.append((t.start[0], "np.load with allow_pickle=True"))
    return out


def test_the_checker_finds_each_form():
    bad = """
import pickle, dill
from pickle import loads
x = pickle.load(f)  # a comment naming pickle.loads is fine
y = pickle.Unpickler(f).load()
z = torch.load(p, map_location="cpu")
w = torch.load(p, weights_only=False)
a = np.load(p, allow_pickle=True)
"""
    found = [what for _, what in violations(bad)]
    assert found == ["the module dill", "from pickle import", "pickle.load", "pickle.Unpickler",
                     "Unpickler", "torch.load without weights_only=True",
                     "torch.load without weights_only=True", "np.load with allow_pickle=True"]
    ok = '''
"""pickle.load and Unpickler in a docstring"""
ck = torch.load(path, map_location=device, weights_only=True)
a = np.load(p, mmap_mode="r", allow_pickle=False)
except pickle.UnpicklingError:
'''
    assert violations(ok) == []


def test_python_pysrc_never_unpickles():
    found = []
    for path in sorted(pathlib.Path(ROOT, "python", "pysrc").rglob("*.py")):
        rel = path.relative_to(ROOT)
        found += [f"{rel}:{line}: {what}" for line, what in
                  violations(path.read_text(encoding="utf-8"))]
    assert found == [], "\n".join(found)
