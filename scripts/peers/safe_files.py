"""Safe writes for the research scripts: the rule the `cellseq` command line keeps
(`crates/cellseq/src/files.rs`), in Python with the standard library only.

`write_text(path, text)` writes a whole file so that a reader never sees half of it and
nothing but the target is ever touched:

- **Regular file or new name**: the text goes to a temporary file in the target's directory,
  `.NAME.RANDOM.tmp` (128 random bits from the operating system), created exclusively
  (`O_CREAT | O_EXCL | O_NOFOLLOW`, mode 0666 less the umask). It is written, flushed to disk,
  renamed over the target, and the directory is flushed. An existing target keeps its
  permission bits.
- **Symbolic link at the target**: the link itself is replaced, never written through, unless
  it leads to a FIFO or a character device (`/dev/stdout`), which is written directly.
- **FIFO or character device**: opened without creating or truncating and written directly.
- **Directory, block device, socket**: refused.

On every error (and on Ctrl-C, SIGTERM or SIGHUP during the write) the temporary file is
removed.

`append_line(path, line)` appends one line to a table (JSON lines), creating it when missing,
without following a symbolic link: a link or anything but a regular file is refused. A line
goes out in one `write` call on an `O_APPEND` descriptor, so two scripts appending to one table
do not lose each other's lines (a rename would).

A refused or failed write raises `WriteError`, a `SystemExit` whose message names the file and
the problem: a script that does not catch it ends with that message and status 1, without a
traceback.
"""

import errno
import os
import secrets
import signal
import stat
import threading


class WriteError(SystemExit):
    """A write refused or failed; the message is "PATH: problem"."""

    def __init__(self, path, problem):
        super().__init__("%s: %s" % (path, problem))
        self.path = path
        self.problem = problem


def _is_stream(mode):
    return stat.S_ISFIFO(mode) or stat.S_ISCHR(mode)


def _classify(path):
    """'replace' with the mode to keep (or None), or 'direct'; raises WriteError otherwise."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return "replace", None
    except OSError as e:
        raise WriteError(path, e.strerror or str(e))
    if stat.S_ISLNK(st.st_mode):
        try:
            if _is_stream(os.stat(path).st_mode):
                return "direct", None
        except OSError:
            pass
        return "replace", None
    if stat.S_ISDIR(st.st_mode):
        raise WriteError(path, "is a directory; give a file name to write")
    if stat.S_ISREG(st.st_mode):
        return "replace", stat.S_IMODE(st.st_mode) & 0o777
    if _is_stream(st.st_mode):
        return "direct", None
    raise WriteError(path, "is a block device, socket or other special file; not written onto")


def _write_all(fd, data):
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _write_direct(path, data):
    fd = os.open(path, os.O_WRONLY | os.O_CLOEXEC)
    try:
        # The node could have been swapped for another kind of file since it was looked at.
        if not _is_stream(os.fstat(fd).st_mode):
            raise WriteError(path, "changed from a FIFO or device to another kind of file")
        _write_all(fd, data)
    finally:
        os.close(fd)


class _CleanupOnSignal:
    """While a temporary file exists, SIGTERM and SIGHUP remove it and end with 128 + signal
    (main thread only; Ctrl-C already arrives as KeyboardInterrupt and unwinds)."""

    def __init__(self, temp):
        self.temp = temp
        self.saved = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGHUP):
                self.saved[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, _frame):
        raise SystemExit(128 + signum)

    def __exit__(self, *exc):
        for sig, old in self.saved.items():
            signal.signal(sig, old)
        return False


def _write_replace(path, keep_mode, data):
    directory, name = os.path.split(path)
    if not name:
        raise WriteError(path, "not a file name to write")
    directory = directory or "."
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
    for _ in range(8):
        temp = os.path.join(directory, ".%s.%s.tmp" % (name[:100], secrets.token_hex(16)))
        try:
            fd = os.open(temp, flags, 0o666)
            break
        except FileExistsError:
            continue  # not ours: never removed; another random name is tried
        except OSError as e:
            raise WriteError(path, e.strerror or str(e))
    else:
        raise WriteError(path, "no free temporary name beside it")
    done = False
    try:
        with _CleanupOnSignal(temp):
            try:
                if keep_mode is not None:
                    os.fchmod(fd, keep_mode)
                _write_all(fd, data)
                os.fsync(fd)
            finally:
                os.close(fd)
            os.replace(temp, path)
            done = True
    except OSError as e:
        raise WriteError(path, e.strerror or str(e))
    finally:
        if not done:
            try:
                os.unlink(temp)
            except OSError:
                pass
    try:
        dfd = os.open(directory, os.O_RDONLY | os.O_CLOEXEC)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass  # some systems cannot flush a directory


def write_bytes(path, data):
    """Write `data` to `path` safely (see the module documentation)."""
    path = os.fspath(path)
    kind, keep_mode = _classify(path)
    if kind == "direct":
        try:
            _write_direct(path, data)
        except OSError as e:
            raise WriteError(path, e.strerror or str(e))
    else:
        _write_replace(path, keep_mode, data)


def write_text(path, text):
    """Write `text` (UTF-8) to `path` safely (see the module documentation)."""
    write_bytes(path, text.encode("utf-8"))


def append_line(path, line):
    """Append `line` and a newline to the table at `path` (see the module documentation)."""
    path = os.fspath(path)
    try:
        st = os.lstat(path)
        if stat.S_ISLNK(st.st_mode):
            raise WriteError(path, "is a symbolic link; not appended through (remove it)")
        if not stat.S_ISREG(st.st_mode):
            raise WriteError(path, "is not a regular file")
    except FileNotFoundError:
        pass
    flags = os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as e:
        if e.errno == errno.ELOOP:
            raise WriteError(path, "is a symbolic link; not appended through (remove it)")
        raise WriteError(path, e.strerror or str(e))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise WriteError(path, "is not a regular file")
        data = (line.rstrip("\n") + "\n").encode("utf-8")
        n = os.write(fd, data)
        if n != len(data):
            raise WriteError(path, "short write (%d of %d bytes)" % (n, len(data)))
    except OSError as e:
        raise WriteError(path, e.strerror or str(e))
    finally:
        os.close(fd)
