"""The run's log (docs/experiment.md, "Progress, warnings and RUN/log.txt"): stderr as the
user reads it, and every line and every warning in ``RUN/log.txt``.

While :func:`capture` is active (``Experiment.run``):

- ``sys.stderr`` is teed: each line goes to the real stderr and to the log file. A line
  rewritten in place with carriage returns (the trainer's step counter) keeps only what a
  terminal finally shows, and the real stderr gets the rewrites only when it is a terminal,
  so a redirected log has one line per epoch, not one per step update;
- every Python warning (the extension's ``Day2NightWarning`` kinds, such as
  ``NoiseExtrapolatedWarning``, and any other library's) is counted by kind: the first one
  of each kind is printed, every one goes to the log file, and the end of the run prints one
  line with each kind's count.

Nothing is written before the run folder is (``open`` is called after the setup files):
the lines before it are kept and written then. The file is appended to, one ``write`` of
a whole line at a time (``O_APPEND``), so a resumed run adds to it and a killed run leaves
whole lines."""

import collections
import contextlib
import datetime
import io
import os
import sys
import warnings

PREFIX = "[experiment] "


class RunLog:
    """The lines and warnings of one run (see the module's docstring)."""

    def __init__(self, real):
        self.real = real
        self.fd = None
        self.path = None
        self.held = []  # lines before the file is open
        self.counts = collections.Counter()

    def line(self, text):
        """One line of the log file (held until :meth:`open`)."""
        stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        data = f"{stamp} {text}\n".encode("utf-8", "replace")
        if self.fd is None:
            self.held.append(data)
        else:
            os.write(self.fd, data)

    def open(self, path):
        """Start writing the log file at ``path`` (appended to), with the lines held."""
        if self.fd is not None:
            return
        self.fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        self.path = path
        for data in self.held:
            os.write(self.fd, data)
        self.held = []

    def close(self):
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def warning(self, message, category, filename, lineno, file=None, line=None):
        """``warnings.showwarning``: count the kind, log every one, print the first."""
        kind = category.__name__
        self.counts[kind] += 1
        text = str(message).replace("\n", " ")
        self.line(f"warning {kind} ({os.path.basename(str(filename))}:{lineno}): {text}")
        if self.counts[kind] == 1:
            self.real.write(f"{PREFIX}warning {kind}: {text} (the first of its kind; "
                            "the count comes at the end of the run)\n")
            self.real.flush()

    def summary(self):
        """The end-of-run line of the warning counts, or None without warnings."""
        if not self.counts:
            return None
        kinds = ", ".join(f"{k} x{n}" for k, n in sorted(self.counts.items()))
        where = (f"every one in {self.path}" if self.fd is not None else
                 "not written to a log file: the run stopped before its run folder")
        return f"warnings of this run: {kinds} ({where})"


class _Tee(io.TextIOBase):
    """``sys.stderr`` while a run is logged: lines to the real stream and to the log."""

    def __init__(self, real, log):
        self.real, self.log, self.pending = real, log, ""
        try:
            self.tty = real.isatty()
        except (AttributeError, ValueError):
            self.tty = False

    def write(self, s):
        if self.tty:
            self.real.write(s)
        self.pending += s
        *done, self.pending = self.pending.split("\n")
        for text in done:
            shown = text.rsplit("\r", 1)[-1]  # what a terminal finally shows
            if not self.tty:
                self.real.write(shown + "\n")
            self.log.line(shown)
        return len(s)

    def flush(self):
        self.real.flush()

    def isatty(self):
        return self.tty

    def fileno(self):
        return self.real.fileno()

    @property
    def encoding(self):
        return getattr(self.real, "encoding", "utf-8")

    def finish(self):
        if self.pending:
            self.write("\n")


@contextlib.contextmanager
def capture():
    """Log the run (the module's docstring); yields the :class:`RunLog` (``open`` it once
    the run folder exists). The warning counts are printed when the run ends, also when it
    fails or is interrupted."""
    real = sys.stderr
    log = RunLog(real)
    tee = _Tee(real, log)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")  # every one counted, not once per place
            warnings.showwarning = log.warning
            sys.stderr = tee
            try:
                yield log
            finally:
                tee.finish()
                sys.stderr = real
                done = log.summary()
                if done:
                    log.line(PREFIX + done)
                    print(PREFIX + done, file=real, flush=True)
    finally:
        log.close()
