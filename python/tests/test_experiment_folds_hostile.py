"""Hostile fold files (issue 42): the release's fold pickle is read as data by
experiment/foldpickle.py, never unpickled. Each reproducer of the issue is built here, byte by
byte from pickle's opcodes, and must be refused with a one-line FoldError naming the file
(exit 2 from the command line, nothing written), in bounded memory (a subprocess under an
address-space limit of 100 MB above its baseline) and bounded work (the reader counts its
opcodes and the items it moves). A seeded mutation test feeds a few thousand damaged copies of
a release-shaped pickle to the reader: each is refused or read exactly as pickle's own
semantics read it."""

import hashlib
import io
import json
import os
import pickle
import random
import subprocess
import sys

import numpy as np
import pytest

from conftest import need_torch
from day2night.experiment import folds, foldpickle, protocol, release_folds

P = pickle
KEYS = release_folds.KEYS


def release_lists(n=105, k=3, val=10, scalar=np.int32):
    """Lists shaped like the release's k_fold_indices_saved.p (docs/experiment.md): sorted,
    train and val entries numpy integer scalars, test entries Python ints."""
    perm = np.random.RandomState(7).permutation(n)
    out = {key: [] for key in KEYS}
    for i in range(k):
        test = sorted(int(j) for j in perm[i::k])
        rest = [j for j in range(n) if j not in set(test)]
        vals = sorted(rest[j] for j in np.random.RandomState(i).permutation(len(rest))[:val])
        train = [j for j in rest if j not in set(vals)]
        out["train_index_all"].append([scalar(j) for j in train])
        out["val_index_all"].append([scalar(j) for j in vals])
        out["test_index_all"].append(test)
    return out


def plain(lists):
    return {k: [[int(j) for j in f] for f in v] for k, v in lists.items()}


# -- pickle bytes by hand ---------------------------------------------------------------------

def text(s):
    b = s.encode()
    return P.SHORT_BINUNICODE + bytes([len(b)]) + b


def glob(module, name):
    return P.GLOBAL + f"{module}\n{name}\n".encode()


def int1(v):
    return P.BININT1 + bytes([v])


def folds_dict(train=None, val=None, test=None):
    """A protocol-4 pickle of the three keys; each value the opcodes of one list of folds
    (default: one fold [[1]], [[2]], [[3]])."""
    one = [P.EMPTY_LIST + P.EMPTY_LIST + int1(v) + P.APPEND + P.APPEND for v in (1, 2, 3)]
    parts = [train or one[0], val or one[1], test or one[2]]
    body = b"".join(text(k) + v for k, v in zip(KEYS, parts))
    return P.PROTO + b"\x04" + P.EMPTY_DICT + P.MARK + body + P.SETITEMS + P.STOP


def in_fold(item_ops):
    """A list of one fold holding the values the opcodes ``item_ops`` push."""
    return P.EMPTY_LIST + P.EMPTY_LIST + P.MARK + item_ops + P.APPENDS + P.APPEND


STATE = (P.MARK + int1(3) + text("<") + P.NONE * 3 + P.BININT + (-1).to_bytes(4, "little",
         signed=True) + P.BININT + (-1).to_bytes(4, "little", signed=True) + int1(0) + P.TUPLE)


def object_pointer():
    """The pointer case: ``dtype('O', False, True)``, its flags cleared by BUILD, then
    ``scalar(dtype, 8 bytes)``: an object scalar whose PyObject* is 8 bytes of the file."""
    return (P.PROTO + b"\x04" + glob("numpy.core.multiarray", "scalar")
            + glob("numpy", "dtype") + text("O") + P.NEWFALSE + P.NEWTRUE + P.TUPLE3 + P.REDUCE
            + STATE.replace(text("<"), text("|")) + P.BUILD
            + P.SHORT_BINBYTES + b"\x08" + b"\x41" * 8 + P.TUPLE2 + P.REDUCE + P.STOP)


def null_pointer_popped():
    """The variant that ran to the end: the object scalar popped before a valid dict."""
    return object_pointer()[:-1] + P.POP + folds_dict()[2:]


def deep_tuple(depth=300_000):
    """A tuple ``depth`` deep used as a dict key (hash() recursion)."""
    return (P.PROTO + b"\x04" + P.EMPTY_DICT + P.EMPTY_TUPLE + P.TUPLE1 * depth + int1(1)
            + P.SETITEM + P.STOP)


def deep_lists(depth=100_000):
    return (P.PROTO + b"\x04" + P.EMPTY_DICT + text(KEYS[0]) + P.EMPTY_LIST * depth
            + P.APPEND * (depth - 1) + P.SETITEM + P.STOP)


def memo_bomb(rounds=60):
    """A small pickle whose memo doubles a value ``rounds`` times (2^60 leaves): tuples of
    the previous tuple twice, and the same with lists."""
    step = P.BINGET + b"\x00" + P.BINGET + b"\x00" + P.TUPLE2 + P.BINPUT + b"\x00"
    tuples = P.PROTO + b"\x04" + int1(1) + P.BINPUT + b"\x00" + step * rounds + P.STOP
    lstep = (P.EMPTY_LIST + P.BINGET + b"\x00" + P.APPEND + P.BINGET + b"\x00" + P.APPEND
             + P.BINPUT + b"\x00")
    lists = P.PROTO + b"\x04" + P.EMPTY_LIST + P.BINPUT + b"\x00" + lstep * rounds + P.STOP
    return tuples, lists


def long_binput(index=0xFFFFFFF0):
    """One LONG_BINPUT with a huge index (CPython's memo array grows 16 bytes per unit)."""
    return P.PROTO + b"\x04" + int1(1) + P.LONG_BINPUT + index.to_bytes(4, "little") + P.STOP


def duplicates_pickle(n=390_000):
    return folds_dict(train=in_fold(int1(3) * n))


def write(tmp_path, name, data):
    p = tmp_path / name
    p.write_bytes(data if isinstance(data, bytes) else data.encode())
    return p


def refused(path, match):
    with pytest.raises(folds.FoldError, match=match) as e:
        release_folds.read_release_folds(path)
    msg = str(e.value)
    assert msg.startswith(f"--folds-file {path}: ") and "\n" not in msg and len(msg) < 600
    return msg


# -- each reproducer refused ------------------------------------------------------------------

@pytest.mark.parametrize("name, make, match", [
    ("pointer.p", object_pointer, r"numpy\.dtype\('O', False, True\): only the integer"),
    ("null.p", null_pointer_popped, r"numpy\.dtype\('O'"),
    ("tuple.p", deep_tuple, "a tuple holding a tuple"),
    ("lists.p", deep_lists, "lists nested deeper"),
    ("bomb_tuples.p", lambda: memo_bomb()[0], "a tuple holding a tuple"),
    ("bomb_lists.p", lambda: memo_bomb()[1], "a list taken from the memo a second time"),
    ("binput.p", long_binput, "memo index 4294967280"),
    ("dups.p", duplicates_pickle, "train_index_all.0. holds index 3 390000 times"),
    ("codecs.p", lambda: pickle.dumps(release_lists(), protocol=2), "_codecs.encode"),
    ("timedelta.p", lambda: pickle.dumps({**plain(release_lists()),
                                          "test_index_all": [[np.timedelta64(3)]]}),
     r"numpy\.dtype\('m8'"),
    ("float.p", lambda: pickle.dumps({**plain(release_lists()), "val_index_all": [[1.5]]}),
     "BINFLOAT"),
    ("long.p", lambda: P.PROTO + b"\x02" + P.LONG + b"9" * 5001 + b"L\n" + P.STOP,
     "opcode LONG is not"),
    ("long1.p", lambda: P.PROTO + b"\x02" + P.LONG1 + b"\xff" + b"\x01" * 255 + P.STOP,
     "an integer of 255 bytes"),
    ("trailing.p", lambda: folds_dict() + b"\x00", "1 bytes after the pickle's STOP"),
    ("truncated.p", lambda: folds_dict()[:-5], "truncated"),
    ("proto0.p", lambda: pickle.dumps(plain(release_lists()), protocol=0), "protocol 2"),
])
def test_each_hostile_pickle_is_refused_naming_the_file(tmp_path, name, make, match):
    data = make()
    refused(write(tmp_path, name, data), match)
    r = foldpickle.Reader(data)
    try:
        r.read()  # only the duplicates pass the reader: release_folds refuses them
        assert name == "dups.p"
    except foldpickle.PickleRefused:
        pass
    # bounded work: never more opcodes than bytes, never more moves than bytes
    assert r.ops <= min(len(data), foldpickle.MAX_OPS) and r.work <= len(data)


def test_the_scalar_case_never_reaches_numpy(tmp_path):
    # every accepted dtype makes a plain int; the object dtype's bytes are never a pointer
    msg = refused(write(tmp_path, "pointer.p", object_pointer()), "only the integer dtypes")
    assert "byte " in msg


@pytest.mark.parametrize("name, data, match", [
    ("deep.json", "[" * 3000 + "]" * 3000, "nested deeper than 3"),
    ("deep_in_string.json", '{"x": "' + "[" * 3000 + '"}', "keys"),
    ("digits.json", '{"train_index_all": [[' + "7" * 5001 + ']]}', "a number of 5001 digits"),
    ("key_twice.json", '{"train_index_all": [[1]], "train_index_all": [[2]]}', "twice"),
    ("dups.json", json.dumps({"train_index_all": [[3] * 390_000], "val_index_all": [[1]],
                              "test_index_all": [[2]]}, separators=(",", ":")),
     r"train_index_all\[0\] holds index 3 390000 times"),
    ("dups_small.json", json.dumps({"train_index_all": [[3, 4, 5, 3, 3, 3, 3]],
                                    "val_index_all": [[1]], "test_index_all": [[2]]}),
     r"holds index 3 5 times: each scene is listed once per fold"),
    ("notutf8.json", b'{"train_index_all": "\xff"}', "not UTF-8"),
])
def test_each_hostile_json_export_is_refused_naming_the_file(tmp_path, name, data, match):
    refused(write(tmp_path, name, data), match)


def test_a_bom_before_the_json_export_is_skipped(tmp_path):
    lists = plain(release_lists())
    p = write(tmp_path, "bom.json", b"\xef\xbb\xbf" + json.dumps(lists).encode())
    assert release_folds.read_release_folds(p) == lists


def test_a_fifo_a_device_and_a_folder_are_refused_before_reading(tmp_path):
    fifo = tmp_path / "fifo.p"
    os.mkfifo(fifo)  # nobody writes it: a blocking open or read would never return
    refused(fifo, "not a regular file")
    refused("/dev/zero", "not a regular file")
    refused(tmp_path, "not a regular file")
    big = write(tmp_path, "big.p", b"\x80\x04" + b"N" * release_folds.MAX_BYTES)
    refused(big, f"larger than {release_folds.MAX_BYTES}")
    # the run's hash is of the same capped bytes: the FIFO and the device never block it
    for p in (fifo, "/dev/zero"):
        with pytest.raises(protocol.ProtocolError, match="not a regular file"):
            protocol.fold_file(p)


def test_the_hash_is_of_the_bytes_read(tmp_path):
    p = write(tmp_path, "k.p", pickle.dumps(release_lists()))
    lists, sha = release_folds.read_release_file(p)
    assert sha == hashlib.sha256(p.read_bytes()).hexdigest()
    assert protocol.fold_file(p)[1:] == (sha, 3)
    scenes = ["%03d" % j for j in range(105)]
    m = release_folds.make_run_folds(scenes, folds_file=p, folds_sha256=sha)
    assert m["splits"][0]["test"] == ["%03d" % j for j in lists["test_index_all"][0]]
    with pytest.raises(folds.FoldError, match="changed while the run started"):
        release_folds.make_run_folds(scenes, folds_file=p, folds_sha256="0" * 64)


@pytest.mark.parametrize("scalar", [np.int32, np.int64])
@pytest.mark.parametrize("proto", [3, 4, 5])
def test_the_release_shapes_are_read(tmp_path, scalar, proto):
    lists = release_lists(scalar=scalar)
    data = pickle.dumps(lists, protocol=proto)
    r = foldpickle.Reader(data)
    assert r.read() == plain(lists)
    assert r.ops < len(data) and r.work < len(data)


def test_the_command_lines_refuse_with_one_line_and_write_nothing(tmp_path, capsys):
    bad = write(tmp_path, "pointer.p", object_pointer())
    out = tmp_path / "out.json"
    assert release_folds.main(["export", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--folds-file {bad}: refused" in err
    assert not out.exists()
    good = write(tmp_path, "k.p", pickle.dumps(release_lists()))
    assert release_folds.main(["export", str(good), "-o", str(good / "x.json")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    need_torch()
    from day2night.experiment.__main__ import main

    run = tmp_path / "run"
    code = main(["--day", str(tmp_path), "--real", str(tmp_path), "-o", str(run),
                 "--protocol", "release", "--folds-file", str(bad)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"--folds-file {bad}: refused" in err
    assert not run.exists()


# -- bounded memory -----------------------------------------------------------------------------

MEMORY_PROBE = r"""
import json, resource, sys
from day2night.experiment import folds, release_folds
def vm():
    for line in open("/proc/self/status"):
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
base = vm()
resource.setrlimit(resource.RLIMIT_AS, (base + 100 * 2**20, resource.RLIM_INFINITY))
out = {}
for path in sys.argv[1:]:
    try:
        release_folds.read_release_folds(path)
        out[path] = "accepted"
    except folds.FoldError as e:
        out[path] = "refused: " + str(e)[:300]
    except MemoryError:
        out[path] = "MemoryError"
print(json.dumps(out))
"""


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs /proc (Linux)")
def test_every_hostile_input_stays_under_100_mb(tmp_path):
    """Each reproducer read in a subprocess whose address space is capped at its baseline
    (interpreter, numpy and the package imported) plus 100 MB."""
    biggest = folds_dict(train=in_fold(b"".join(P.BININT + j.to_bytes(4, "little")
                                                for j in range(200_000))))
    cases = {
        "pointer.p": object_pointer(), "tuple.p": deep_tuple(), "lists.p": deep_lists(),
        "bomb_t.p": memo_bomb()[0], "bomb_l.p": memo_bomb()[1], "binput.p": long_binput(),
        "dups.p": duplicates_pickle(), "biggest.p": biggest,
        "deep.json": "[" * 500_000 + "]" * 500_000,
        "dups.json": '{"train_index_all": [[' + "3," * 520_000 + "3]]}",
    }
    paths = [str(write(tmp_path, n, d)) for n, d in cases.items()] + ["/dev/zero"]
    r = subprocess.run([sys.executable, "-c", MEMORY_PROBE, *paths], capture_output=True,
                       text=True, env=os.environ)
    assert r.returncode == 0, r.stderr[-2000:]
    got = json.loads(r.stdout)
    assert got[str(tmp_path / "biggest.p")] == "accepted"
    for p in paths:
        if not p.endswith("biggest.p"):
            assert got[p].startswith(f"refused: --folds-file {p}: "), (p, got[p])


# -- the mutation property test -------------------------------------------------------------------

class _Reference(pickle.Unpickler):
    """pickle's own semantics, for files the reader ACCEPTED only (their dtypes are then
    checked integer dtypes, so loading them cannot reach an object pointer)."""

    def find_class(self, module, name):
        if (module, name) in foldpickle.SCALAR_NAMES:
            return np.int64(0).__reduce__()[0]  # numpy's scalar constructor
        if (module, name) in foldpickle.DTYPE_NAMES:
            return np.dtype
        raise pickle.UnpicklingError(f"{module}.{name}")


def _mutate(rng, data):
    b = bytearray(data)
    for _ in range(rng.randint(1, 3)):
        if not b:
            break
        kind, i = rng.randrange(4), rng.randrange(len(b))
        if kind == 0:
            b[i] = rng.randrange(256)
        elif kind == 1:
            b.insert(i, rng.randrange(256))
        elif kind == 2:
            del b[i]
        else:
            del b[rng.randrange(len(b)):]
    return bytes(b)


def test_mutated_release_pickles_are_refused_or_read_as_pickle_reads_them():
    rng = random.Random(42)
    bases = [pickle.dumps(release_lists(scalar=s), protocol=p)
             for s in (np.int32, np.int64) for p in (3, 4)]
    outcomes = {"refused": 0, "equal": 0}
    for _ in range(3000):
        data = _mutate(rng, rng.choice(bases))
        try:
            got = release_folds.parse("m.p", data)
        except folds.FoldError as e:
            assert str(e).startswith("--folds-file m.p: ") and "\n" not in str(e)
            outcomes["refused"] += 1
            continue
        want = _Reference(io.BytesIO(data)).load()
        assert got == plain(want)
        outcomes["equal"] += 1
    # both branches are exercised (a mutation of an index's bytes reads as another index)
    assert outcomes["refused"] > 2000 and outcomes["equal"] > 10, outcomes
