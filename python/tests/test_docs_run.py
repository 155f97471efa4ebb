"""Docs that run: every shell command and Python snippet of README.md, python/README.md and
docs/*.md runs here, as rustdoc runs doc examples (tests/README.md, "Docs that run").

Fenced blocks tagged `sh`, `bash` or `console` (its `$ ` lines) run with bash -e in a
temporary folder per document, in the document's order, with `day2night` on PATH (the CLI
of D2N_BIN; `cargo run --release --` in a command means it too), `python` the interpreter
running the tests (with the package), and a copy of `fixtures/` in the folder. `python`
blocks run in one namespace per document, in the same folder. A failure names the
document, the line of the block and the error. Shell blocks also get D2N_ROOT, the
repository's root (a setup may link a folder of it, e.g. `python`, to stand for the clone).

An HTML comment right before a block (blank lines between allowed) changes that:

    <!-- docs-run: skip (REASON) -->      not run (a cluster, a GPU, PyPI, the user's own
                                          files...); counted and listed
    <!-- docs-run: setup
    COMMANDS OR CODE -->                  run first, in the block's language (e.g. make
                                          card_*.dng from the fixture); not shown to readers
    <!-- docs-run: needs MODULE -->       a block that needs the Python module MODULE
                                          (e.g. torch): skipped, with the reason, when the
                                          test interpreter cannot import it
    <!-- docs-run: slow (REASON) -->      run only with D2N_SLOW=1 (`scripts/test.sh --slow`
                                          sets it): a block of minutes, such as a training
                                          run; skipped with REASON otherwise

Every fenced block names its language (`text` for diagrams, synopses and output), so a
command cannot hide in an untagged block. Also checked: repository paths named in the docs
exist, no doc names a file outside the repository, `cargo test --test NAME` names a test
target."""

import contextlib
import glob
import io
import os
import pathlib
import re
import shutil
import subprocess
import sys
import traceback

import pytest

from conftest import ROOT, cli_path

DOCS = [ROOT / "README.md", ROOT / "python" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
RUN = {"sh", "bash", "console", "python"}
# languages of blocks that are not commands: shown, never run
SHOWN = {"text", "json", "yaml", "rust", "rust,no_run", "rust,ignore", "toml", "diff"}
# docs/cli.md is generated from --help (tests/it/cli_docs.rs); its blocks are `text`
FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
MARK = re.compile(r"<!--\s*docs-run:\s*(skip|setup|needs|slow)\b(.*?)-->", re.S)


class Block:
    def __init__(self, doc, line, lang, code):
        self.doc, self.line, self.lang, self.code = doc, line, lang, code
        self.skip = self.setup = self.needs = self.slow = None

    @property
    def where(self):
        doc = self.doc.relative_to(ROOT) if self.doc.is_relative_to(ROOT) else self.doc
        return f"{doc}:{self.line}"


def blocks(doc):
    """The fenced blocks of DOC with their markers; fails on a malformed marker."""
    lines = doc.read_text(encoding="utf-8").split("\n")
    out, i, pending, last_end = [], 0, [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang = m.group(1), m.group(2)
        j = i + 1
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            j += 1
        assert j < len(lines), f"{doc.relative_to(ROOT)}:{i + 1}: unclosed code block"
        code = "\n".join(l[len(indent):] if l.startswith(indent) else l for l in lines[i + 1:j])
        b = Block(doc, i + 1, lang, code)
        # markers: the HTML comments between the previous block (or text) and this fence
        k = i - 1
        while k >= last_end and lines[k].strip() == "":
            k -= 1
        text_before = "\n".join(lines[last_end:k + 1])
        tail = text_before[text_before.rfind("\n\n") + 1:] if "\n\n" in text_before else text_before
        for mk in MARK.finditer(tail):
            kind, arg = mk.group(1), mk.group(2).strip()
            if kind in ("skip", "slow"):
                assert re.fullmatch(r"\(.+\)", arg, re.S), \
                    f"{b.where}: docs-run: {kind} needs a reason in parentheses"
                setattr(b, kind, arg[1:-1])
            elif kind == "setup":
                b.setup = arg
            else:
                b.needs = arg
        out.append(b)
        last_end = j + 1
        i = j + 1
    return out


ALL = [b for d in DOCS for b in blocks(d)]
RUNNABLE = [b for b in ALL if b.lang in RUN]


def test_every_block_names_its_language():
    bad = [f"{b.where}: ```{b.lang}" for b in ALL if b.lang not in RUN | SHOWN]
    assert not bad, "untagged or unknown code blocks (tag them; tests/README.md):\n" + "\n".join(bad)


def test_markers_are_on_runnable_blocks():
    bad = [b.where for b in ALL if b.lang not in RUN and (b.skip or b.setup or b.needs or b.slow)]
    assert not bad, f"docs-run markers on blocks that never run: {bad}"


def test_skipped_blocks_are_counted():
    """Prints the count (pytest -s, or -rA) and every skipped block with its reason."""
    skipped = [f"{b.where} ({b.skip})" for b in RUNNABLE if b.skip]
    slow = [f"{b.where} ({b.slow})" for b in RUNNABLE if b.slow and not b.skip]
    print(f"docs-run: {len(slow)} slow block(s), run with D2N_SLOW=1:\n  " + "\n  ".join(slow))
    print(f"docs-run: {len(RUNNABLE) - len(skipped)} of {len(RUNNABLE)} blocks run, "
          f"{len(skipped)} skipped with a reason:\n  " + "\n  ".join(skipped))
    assert all(b.skip.strip() for b in RUNNABLE if b.skip is not None), "a skip without a reason"


@pytest.fixture(scope="module")
def workdirs(tmp_path_factory):
    """One folder per document (blocks of a document share it, in order), with a copy of
    fixtures/, `day2night` and `python` on PATH, and one Python namespace."""
    bindir = tmp_path_factory.mktemp("bin")
    (bindir / "day2night").symlink_to(cli_path())
    for name in ("python", "python3"):  # a wrapper, not a link: a venv is found by its path
        (bindir / name).write_text(f'#!/bin/sh\nexec "{sys.executable}" "$@"\n')
        (bindir / name).chmod(0o755)
    dirs = {}

    def get(doc):
        if doc not in dirs:
            d = tmp_path_factory.mktemp(doc.stem)
            shutil.copytree(ROOT / "fixtures", d / "fixtures")
            dirs[doc] = (d, {"__name__": "__docs_run__"})
        return dirs[doc]

    get.bindir = bindir
    return get


def shell_script(b):
    code = b.code
    if b.lang == "console":
        cmds, cont = [], False
        for line in code.split("\n"):
            if line.startswith("$ ") or cont:
                cmd = line[2:] if line.startswith("$ ") and not cont else line
                cmds.append(cmd)
                cont = cmd.rstrip().endswith("\\")
        code = "\n".join(cmds)
    code = code.replace("cargo run --release -- ", "day2night ")
    return (b.setup + "\n" if b.setup else "") + code


@pytest.mark.parametrize("b", RUNNABLE, ids=[f"{b.where}-{b.lang}" for b in RUNNABLE])
def test_documented_block_runs(b, workdirs, monkeypatch):
    if b.skip:
        pytest.skip(f"docs-run: skip ({b.skip})")
    if b.slow and os.environ.get("D2N_SLOW") != "1":
        pytest.skip(f"docs-run: slow ({b.slow}); D2N_SLOW=1 (scripts/test.sh --slow) runs it")
    if b.needs:
        try:
            __import__(b.needs)
        except ImportError as e:
            pytest.skip(f"{b.where} needs {b.needs}: {e}")
    d, ns = workdirs(b.doc)
    if b.lang == "python":
        monkeypatch.chdir(d)
        code = (b.setup + "\n" if b.setup else "") + b.code
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(code, b.where, "exec"), ns)
        except Exception:
            pytest.fail(f"{b.where}: the python block fails:\n{b.code}\n{traceback.format_exc()}")
        return
    env = dict(os.environ, PATH=f"{workdirs.bindir}{os.pathsep}{os.environ['PATH']}",
               D2N_ROOT=str(ROOT))
    r = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", shell_script(b)], cwd=d, env=env,
                       capture_output=True, text=True, timeout=3600 if b.slow else 600)
    if r.returncode != 0:
        pytest.fail(f"{b.where}: the {b.lang} block fails (exit {r.returncode}):\n{b.code}\n"
                    f"--- stderr ---\n{r.stderr[-3000:]}\n--- stdout ---\n{r.stdout[-1000:]}")


def test_markers_are_parsed(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("Text.\n\n<!-- docs-run: slow (a 6-minute run) -->\n<!-- docs-run: needs torch -->"
                   "\n\n```sh\necho hi\n```\n\n```sh\necho plain\n```\n", encoding="utf-8")
    a, b = blocks(doc)
    assert (a.slow, a.needs, a.skip) == ("a 6-minute run", "torch", None)
    assert (b.slow, b.needs, b.skip) == (None, None, None)
    doc.write_text("<!-- docs-run: slow -->\n```sh\necho hi\n```\n", encoding="utf-8")
    with pytest.raises(AssertionError, match="slow needs a reason in parentheses"):
        blocks(doc)


# --- paths and references -------------------------------------------------------------------

OUTSIDE = re.compile(r"\.\./shared|SYNTHESIS\.md|CLI\.md")
PATH_RE = re.compile(
    r"(?<![\w./-])((?:src|tests|docs|python|benches|scripts|fixtures|examples|fuzz|\.ci)"
    r"/[\w.*/-]*[\w*/])")


def doc_lines():
    for d in DOCS:
        for n, line in enumerate(d.read_text(encoding="utf-8").split("\n"), 1):
            yield d, n, line


def test_no_doc_names_a_file_outside_the_repository():
    # every text file of docs/ (the figure scripts too), the READMEs
    files = DOCS + [p for p in (ROOT / "docs").rglob("*") if p.suffix in {".py", ".txt", ".sh"}]
    bad = [f"{f.relative_to(ROOT)}:{n}: {line.strip()}" for f in files
           for n, line in enumerate(f.read_text(encoding="utf-8").split("\n"), 1)
           if OUTSIDE.search(line)]
    assert not bad, "docs name files a clone does not have:\n" + "\n".join(bad)


def test_paths_named_in_docs_exist():
    bad = []
    for d, n, line in doc_lines():
        for m in PATH_RE.finditer(line):
            p = m.group(1).rstrip(".")
            if "*" in p:  # a pattern: its folder exists (it may match nothing yet)
                ok = bool(glob.glob(str(ROOT / p))) or (ROOT / p).parent.is_dir()
            else:
                ok = (ROOT / p).exists()
            if not ok:
                bad.append(f"{d.relative_to(ROOT)}:{n}: {p}")
    assert not bad, "paths named in docs that do not exist:\n" + "\n".join(bad)


def test_cargo_test_targets_exist():
    targets = {p.stem for p in (ROOT / "tests").glob("*.rs")}
    targets |= {p.parent.name for p in (ROOT / "tests").glob("*/main.rs")}
    bad = []
    for d, n, line in doc_lines():
        for m in re.finditer(r"cargo test[^`]*?--test\s+([\w-]+)", line):
            if m.group(1) not in targets:
                bad.append(f"{d.relative_to(ROOT)}:{n}: --test {m.group(1)} (targets: {sorted(targets)})")
    assert not bad, "\n".join(bad)
