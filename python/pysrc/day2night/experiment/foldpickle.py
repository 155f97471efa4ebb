"""The release's fold-index pickle (``utils/k_fold_indices_saved.p``) read as data: its
opcodes are walked by a small reader that builds no object of the file's choosing. There is
no ``pickle.load`` and no ``Unpickler`` here: a restricted unpickler is not a boundary for a
file from elsewhere (issue 42: with only ``numpy.dtype`` and numpy's scalar constructor, a
pickle can build an object dtype, clear its flags through BUILD and make a scalar whose
object pointer is 8 bytes of the file).

What is accepted is the shape the release's file has (docs/experiment.md, "The release's
folds"), written by ``pickle.dump`` with protocol 2 to 5:

- one dict (EMPTY_DICT, SETITEM/SETITEMS) of string keys to lists (EMPTY_LIST,
  APPEND/APPENDS) of lists of integers, and nothing deeper;
- an integer is BININT, BININT1, BININT2, LONG1 of at most 8 bytes, or a numpy integer
  scalar: ``scalar(dtype, bytes)`` (REDUCE) of a dtype made by ``dtype(code, False, True)``
  (REDUCE; ``code`` ``i4`` or ``i8``) whose state (BUILD) is exactly numpy's for a
  little-endian integer, the bytes as many as the dtype's size, read by ``int.from_bytes``;
- the only globals (GLOBAL, STACK_GLOBAL) are those two names, as tokens that are never
  looked up; tuples hold only strings, numbers, booleans, None, bytes and those tokens (the
  arguments of REDUCE and the dtype's state);
- the memo (BINPUT, LONG_BINPUT, MEMOIZE; BINGET, LONG_BINGET) holds up to
  :data:`MAX_MEMO` entries at indices below it, and a list or dict is never taken from it,
  so every list is in one place (no sharing, no cycle, no memo bomb).

Every other opcode, global or shape is a :class:`PickleRefused` naming it and its byte
offset. The limits (:data:`MAX_OPS`, :data:`MAX_MARKS`, :data:`MAX_STACK`) are checked as
the opcodes are read, so the work is linear in the file's size."""

MAX_OPS = 600_000
MAX_MEMO = 65_536
MAX_MARKS = 8
MAX_STACK = 600_000
MAX_TUPLE = 8
MAX_GLOBAL_LINE = 64
#: dtype codes of the numpy integer scalars accepted, and their sizes in bytes.
DTYPES = {"i4": 4, "i8": 8}
#: numpy's dtype state (BUILD) of a little-endian integer dtype.
INT_STATE = (3, "<", None, None, None, -1, -1, 0)
SCALAR_NAMES = {("numpy.core.multiarray", "scalar"), ("numpy._core.multiarray", "scalar")}
DTYPE_NAMES = {("numpy", "dtype")}


class PickleRefused(ValueError):
    """A fold-index pickle this reader does not accept (the message says where and why)."""


class _Token:
    """A global of the file, by name only (never imported)."""

    def __init__(self, kind):
        self.kind = kind


SCALAR, DTYPE = _Token("scalar"), _Token("dtype")


class _Dtype:
    """``numpy.dtype(code, False, True)`` as data: its code and whether BUILD set its state."""

    def __init__(self, code):
        self.code, self.built = code, False


class _List(list):
    """A list of the file; ``nested``: it holds lists (the folds of one key)."""

    nested = False


class _Dict(dict):
    """The file's dict."""


SCALARS = (int, str, bytes, bool, type(None), _Token, _Dtype)


def _what(v):
    if isinstance(v, _Token):
        return f"the global {v.kind}"
    return {_List: "a list", _Dict: "a dict", tuple: "a tuple", _Dtype: "a dtype",
            bool: "a boolean", type(None): "None"}.get(type(v), f"a {type(v).__name__}")


class Reader:
    """One pass over ``data``; :meth:`read` returns the dict. ``ops`` counts the opcodes read
    and ``work`` the items moved (both bounded: tests assert it)."""

    def __init__(self, data):
        self.data, self.pos, self.at = bytes(data), 0, 0
        self.stack, self.marks, self.memo = [], [], {}
        self.ops = self.work = 0

    def refuse(self, why):
        raise PickleRefused(f"byte {self.at}: {why}")

    def take(self, n):
        if n < 0 or self.pos + n > len(self.data):
            self.refuse("the pickle is truncated")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return out

    def uint(self, n):
        return int.from_bytes(self.take(n), "little")

    def fence(self):
        return self.marks[-1] if self.marks else 0

    def push(self, v):
        if len(self.stack) >= MAX_STACK:
            self.refuse(f"more than {MAX_STACK} values on the pickle's stack")
        self.stack.append(v)

    def pop(self):
        if len(self.stack) <= self.fence():
            self.refuse("the pickle's stack underflows")
        return self.stack.pop()

    def top(self):
        """The value a list or dict opcode adds to (it stays on the stack)."""
        if len(self.stack) <= self.fence():
            self.refuse("the pickle's stack underflows")
        return self.stack[-1]

    def pop_mark(self):
        if not self.marks:
            self.refuse("no MARK before the opcode that needs one")
        start = self.marks.pop()
        items = self.stack[start:]
        del self.stack[start:]
        self.work += len(items)
        return items

    def read(self):
        """The file's dict {str: list of lists of int (or str)}; PickleRefused otherwise."""
        while True:
            self.at = self.pos
            self.ops += 1
            if self.ops > MAX_OPS:
                self.refuse(f"more than {MAX_OPS} opcodes")
            code = self.take(1)[0]
            if self.ops == 1 and code != 0x80:
                self.refuse("not a pickle of protocol 2 or later (no PROTO opcode first)")
            if code == 0x2E:  # STOP
                return self.stop()
            op = OPCODES.get(code)
            if op is None:
                self.refuse(f"opcode {_opname(code)} is not one a fold-index file holds")
            op(self)

    def stop(self):
        if self.marks or len(self.stack) != 1 or not isinstance(self.stack[0], _Dict):
            what = _what(self.stack[-1]) if self.stack else "nothing"
            self.refuse(f"the pickle ends with {what} where one dict of the fold lists is "
                        "expected")
        if self.pos != len(self.data):
            self.refuse(f"{len(self.data) - self.pos} bytes after the pickle's STOP")
        return {k: ([list(x) if isinstance(x, _List) else x for x in v]
                    if isinstance(v, _List) else v) for k, v in self.stack[0].items()}


def _opname(code):
    names = {0x63: "GLOBAL", 0x93: "STACK_GLOBAL", 0x52: "REDUCE", 0x81: "NEWOBJ",
             0x92: "NEWOBJ_EX", 0x69: "INST", 0x6F: "OBJ", 0x32: "DUP", 0x30: "POP",
             0x31: "POP_MARK", 0x67: "GET", 0x70: "PUT", 0x4C: "LONG", 0x8B: "LONG4",
             0x49: "INT", 0x8D: "BINUNICODE8", 0x8E: "BINBYTES8", 0x96: "BYTEARRAY8",
             0x8F: "EMPTY_SET", 0x90: "ADDITEMS", 0x91: "FROZENSET", 0x97: "NEXT_BUFFER",
             0x98: "READONLY_BUFFER", 0x47: "BINFLOAT", 0x46: "FLOAT"}
    return names.get(code, f"0x{code:02x} ({ascii(chr(code))})")


# -- opcodes ---------------------------------------------------------------------------------

def _proto(r):
    v = r.take(1)[0]
    if r.ops != 1 or not 2 <= v <= 5:
        r.refuse(f"PROTO {v}: a fold-index file is one pickle of protocol 2 to 5")


def _frame(r):
    n = r.uint(8)
    if n > len(r.data) - r.pos:
        r.refuse(f"a FRAME of {n} bytes runs past the end of the file")


def _int_op(n, signed):
    def op(r):
        r.push(int.from_bytes(r.take(n), "little", signed=signed))
    return op


def _long1(r):
    n = r.take(1)[0]
    if n > 8:
        r.refuse(f"an integer of {n} bytes (LONG1): a scene index fits in 8")
    r.push(int.from_bytes(r.take(n), "little", signed=True))


def _text(n):
    def op(r):
        raw = r.take(r.uint(n))
        try:
            r.push(raw.decode("utf-8", "surrogatepass"))
        except UnicodeDecodeError:
            r.refuse("a string that is not UTF-8")
    return op


def _bytes(n):
    def op(r):
        r.push(r.take(r.uint(n)))
    return op


def _const(v):
    def op(r):
        r.push(v)
    return op


def _global(r, module, name):
    if (module, name) in SCALAR_NAMES:
        return SCALAR
    if (module, name) in DTYPE_NAMES:
        return DTYPE
    return r.refuse(f"the global {ascii(module)[1:-1]}.{ascii(name)[1:-1]}: only numpy's scalar constructor and "
                    "numpy.dtype may appear in a fold-index file (and are never imported)")


def _line(r):
    end = r.data.find(b"\n", r.pos, r.pos + MAX_GLOBAL_LINE + 1)
    if end < 0:
        r.refuse(f"a GLOBAL name longer than {MAX_GLOBAL_LINE} bytes or unterminated")
    raw = r.take(end - r.pos + 1)[:-1]
    if not raw.isascii():
        r.refuse("a GLOBAL name that is not ASCII")
    return raw.decode("ascii")


def _global_op(r):
    module = _line(r)
    r.push(_global(r, module, _line(r)))


def _stack_global(r):
    name, module = r.pop(), r.pop()
    if not isinstance(name, str) or not isinstance(module, str):
        r.refuse("STACK_GLOBAL of values that are not strings")
    r.push(_global(r, module, name))


def _mark(r):
    if len(r.marks) >= MAX_MARKS:
        r.refuse(f"MARKs nested more than {MAX_MARKS} deep")
    r.marks.append(len(r.stack))


def _tuple_of(r, items):
    if len(items) > MAX_TUPLE:
        r.refuse(f"a tuple of {len(items)} items (at most {MAX_TUPLE}: REDUCE's arguments "
                 "and a dtype's state)")
    for v in items:
        if not isinstance(v, SCALARS):
            r.refuse(f"a tuple holding {_what(v)}: tuples here hold only numbers, strings "
                     "and numpy's names")
    r.push(tuple(items))


def _tuple_n(n):
    def op(r):
        items = [r.pop() for _ in range(n)][::-1]
        _tuple_of(r, items)
    return op


def _tuple_mark(r):
    _tuple_of(r, r.pop_mark())


def _empty_list(r):
    r.push(_List())


def _empty_dict(r):
    r.push(_Dict())


def _extend(r, target, items):
    if not isinstance(target, _List):
        r.refuse(f"APPEND to {_what(target)}, not a list")
    for v in items:
        if isinstance(v, _List):
            if v.nested:
                r.refuse("lists nested deeper than a list of folds of indices")
            target.nested = True
        elif not isinstance(v, int) or isinstance(v, bool):
            r.refuse(f"{_what(v)} in a list: the lists hold folds of integer indices")
    target.extend(items)


def _append(r):
    v = r.pop()
    _extend(r, r.top(), [v])


def _appends(r):
    items = r.pop_mark()
    _extend(r, r.top(), items)


def _set(r, target, items):
    if not isinstance(target, _Dict):
        r.refuse(f"SETITEM on {_what(target)}, not a dict")
    if len(items) % 2:
        r.refuse("SETITEMS with a key and no value")
    for k, v in zip(items[::2], items[1::2]):
        if not isinstance(k, str):
            r.refuse(f"a dict key that is {_what(k)}, not a string")
        if not isinstance(v, (_List, str)):
            r.refuse(f"the dict's {ascii(k)[:40]} is {_what(v)}, not a list of folds")
        if k in target:
            r.refuse(f"the dict's key {ascii(k)[:40]} appears twice")
        target[k] = v


def _setitem(r):
    v = r.pop()
    k = r.pop()
    _set(r, r.top(), [k, v])


def _setitems(r):
    items = r.pop_mark()
    _set(r, r.top(), items)


def _put(r, i):
    if i >= MAX_MEMO or len(r.memo) >= MAX_MEMO:
        r.refuse(f"memo index {i}: a fold-index file needs fewer than {MAX_MEMO}")
    if len(r.stack) <= r.fence():
        r.refuse("a memo PUT with nothing on the stack")
    r.memo[i] = r.stack[-1]


def _get(r, i):
    if i not in r.memo:
        r.refuse(f"memo index {i} was never stored")
    v = r.memo[i]
    if isinstance(v, (_List, _Dict)):
        r.refuse(f"{_what(v)} taken from the memo a second time (shared or cyclic lists)")
    r.push(v)


def _reduce(r):
    args, fn = r.pop(), r.pop()
    if not isinstance(args, tuple):
        r.refuse(f"REDUCE with {_what(args)} for arguments")
    if fn is DTYPE:
        ok = len(args) == 3 and args[0] in DTYPES and args[1] in (False, 0) \
            and args[2] in (True, 1) and all(not isinstance(a, (bytes, _Dtype, _Token))
                                            for a in args)
        if not ok:
            r.refuse(f"numpy.dtype{_short(args)}: only the integer dtypes "
                     f"{', '.join(DTYPES)} are accepted")
        r.push(_Dtype(args[0]))
        return
    if fn is SCALAR:
        r.push(_scalar(r, args))
        return
    r.refuse(f"REDUCE of {_what(fn)}")


def _scalar(r, args):
    if len(args) != 2 or not isinstance(args[0], _Dtype) or not isinstance(args[1], bytes):
        r.refuse(f"numpy scalar{_short(args)}: not (integer dtype, bytes)")
    dtype, raw = args
    if not dtype.built:
        r.refuse("a numpy scalar of a dtype whose state was never set (BUILD)")
    if len(raw) != DTYPES[dtype.code]:
        r.refuse(f"a numpy {dtype.code} scalar of {len(raw)} bytes")
    return int.from_bytes(raw, "little", signed=True)


def _short(args):
    text = ", ".join(_what(a) if isinstance(a, (_Token, _Dtype)) else ascii(a)[:20]
                     for a in args[:4])
    return f"({text}{', ...' if len(args) > 4 else ''})"


def _build(r):
    state, obj = r.pop(), r.pop()
    if not isinstance(obj, _Dtype):
        r.refuse(f"BUILD of {_what(obj)}: only a dtype's state is set in a fold-index file")
    if obj.built:
        r.refuse("BUILD of a dtype whose state is already set")
    if not isinstance(state, tuple) or len(state) != len(INT_STATE) or any(
            type(a) is not type(b) or a != b for a, b in zip(state, INT_STATE)):
        r.refuse(f"the dtype state {_short(state) if isinstance(state, tuple) else _what(state)}"
                 f" is not a little-endian integer's {INT_STATE}")
    obj.built = True
    r.push(obj)


OPCODES = {
    0x80: _proto, 0x95: _frame,
    0x4A: _int_op(4, True), 0x4B: _int_op(1, False), 0x4D: _int_op(2, False), 0x8A: _long1,
    0x58: _text(4), 0x8C: _text(1), 0x42: _bytes(4), 0x43: _bytes(1),
    0x4E: _const(None), 0x88: _const(True), 0x89: _const(False),
    0x63: _global_op, 0x93: _stack_global, 0x28: _mark,
    0x29: lambda r: r.push(()), 0x74: _tuple_mark, 0x85: _tuple_n(1), 0x86: _tuple_n(2),
    0x87: _tuple_n(3),
    0x5D: _empty_list, 0x61: _append, 0x65: _appends,
    0x7D: _empty_dict, 0x73: _setitem, 0x75: _setitems,
    0x71: lambda r: _put(r, r.uint(1)), 0x72: lambda r: _put(r, r.uint(4)),
    0x94: lambda r: _put(r, len(r.memo)),
    0x68: lambda r: _get(r, r.uint(1)), 0x6A: lambda r: _get(r, r.uint(4)),
    0x52: _reduce, 0x62: _build,
}


def read(data):
    """The dict of a fold-index pickle's bytes (see the module); PickleRefused otherwise."""
    return Reader(data).read()
