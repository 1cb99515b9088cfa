"""scripts/peers/safe_files.py: the research scripts write as the command line does (temporary
file and rename, never through a planted link, never onto a special file, no leftovers)."""

import errno
import json
import os
import signal
import stat
import subprocess
import sys
import time

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
PEERS = os.path.join(ROOT, "scripts", "peers")
sys.path.insert(0, PEERS)

import safe_files  # noqa: E402


def leftovers(d):
    return sorted(n for n in os.listdir(d) if n.endswith(".tmp"))


def test_writes_a_new_file_and_replaces_one_keeping_its_mode(tmp_path):
    p = tmp_path / "out.md"
    safe_files.write_text(p, "one\n")
    assert p.read_text() == "one\n"
    os.chmod(p, 0o640)
    safe_files.write_text(p, "two\n")
    assert p.read_text() == "two\n"
    assert stat.S_IMODE(os.stat(p).st_mode) == 0o640
    assert leftovers(tmp_path) == []


def test_a_planted_link_is_replaced_never_written_through(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("keep me\n")
    out = tmp_path / "out.jsonl"
    os.symlink(victim, out)
    safe_files.write_text(out, "new\n")
    assert victim.read_text() == "keep me\n"
    assert not os.path.islink(out) and out.read_text() == "new\n"
    # appending through a link is refused, naming the file
    os.unlink(out)
    os.symlink(victim, out)
    with pytest.raises(safe_files.WriteError) as e:
        safe_files.append_line(out, "{}")
    assert str(out) in str(e.value) and "symbolic link" in str(e.value)
    assert victim.read_text() == "keep me\n"


def test_a_directory_is_refused_and_a_fifo_is_written_directly(tmp_path):
    with pytest.raises(safe_files.WriteError) as e:
        safe_files.write_text(tmp_path, "x")
    assert "is a directory" in str(e.value)
    with pytest.raises(safe_files.WriteError):
        safe_files.append_line(tmp_path, "x")
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    reader = subprocess.Popen(["cat", str(fifo)], stdout=subprocess.PIPE)
    safe_files.write_text(fifo, "through the pipe\n")
    assert reader.communicate(timeout=10)[0] == b"through the pipe\n"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)  # the node stays a FIFO
    with pytest.raises(safe_files.WriteError) as e:
        safe_files.append_line(fifo, "x")
    assert "not a regular file" in str(e.value)
    assert leftovers(tmp_path) == []


def test_appends_lines_and_a_failed_write_leaves_no_temporary(tmp_path, monkeypatch):
    t = tmp_path / "runs.jsonl"
    for i in range(3):
        safe_files.append_line(t, json.dumps({"i": i}))
    assert [json.loads(x)["i"] for x in t.read_text().splitlines()] == [0, 1, 2]
    # a directory that is not there: no temporary file can be made; the error names the target
    with pytest.raises(safe_files.WriteError) as e:
        safe_files.write_text(tmp_path / "missing" / "x.md", "x")
    assert str(tmp_path / "missing" / "x.md") in str(e.value)
    # a write that fails halfway (a full disk): the old text stays, the temporary file goes
    old = tmp_path / "old.md"
    old.write_text("old\n")

    def full(fd, data):
        os.write(fd, data[:1])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(safe_files, "_write_all", full)
    with pytest.raises(safe_files.WriteError) as e:
        safe_files.write_text(old, "new text\n")
    assert str(old) in str(e.value) and "No space" in str(e.value)
    assert old.read_text() == "old\n"
    assert leftovers(tmp_path) == []


def test_a_script_killed_while_writing_leaves_the_old_file_and_no_temporary(tmp_path):
    """SIGTERM during a slow write: the target keeps its old text, the temporary file is
    removed and the status is 128 + 15."""
    out = tmp_path / "table.md"
    out.write_text("old\n")
    child = (
        "import os, sys, time\n"
        "sys.path.insert(0, %r)\n"
        "import safe_files\n"
        "real = safe_files._write_all\n"
        "def slow(fd, data):\n"
        "    real(fd, data[:1])\n"
        "    open(%r, 'w').close()\n"
        "    time.sleep(30)\n"
        "safe_files._write_all = slow\n"
        "safe_files.write_text(%r, 'new text\\n')\n"
    ) % (PEERS, str(tmp_path / "paused"), str(out))
    p = subprocess.Popen([sys.executable, "-c", child])
    deadline = time.monotonic() + 20
    while not (tmp_path / "paused").exists():
        assert time.monotonic() < deadline and p.poll() is None
        time.sleep(0.02)
    assert len(leftovers(tmp_path)) == 1
    p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=20) == 128 + signal.SIGTERM
    assert out.read_text() == "old\n"
    assert leftovers(tmp_path) == []


def test_a_script_ends_with_the_file_and_the_problem_not_a_traceback(tmp_path):
    """`sequence_diff.py --out` onto a directory: status 1, the message names the file."""
    sop = tmp_path / "i.sop"
    n = 4
    M = [[0 if i == j else 1 for j in range(n)] for i in range(n)]
    for i in range(1, n):
        M[i][0] = -1
    for j in range(n - 1):
        M[n - 1][j] = -1
    import sop_common

    sop_common.write_sop(sop, "i", M)
    sol = tmp_path / "a.json"
    sol.write_text(json.dumps({"sequence": [{"cell": str(v + 1), "mode": 0} for v in range(n)]}))
    target = tmp_path / "dir"
    target.mkdir()
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "sequence_diff.py"),
                        str(sop), str(sol), "--window", "1", "2", "--out", str(target)],
                       capture_output=True, text=True)
    assert r.returncode == 1, r
    assert str(target) in r.stderr and "is a directory" in r.stderr
    assert "Traceback" not in r.stderr
