#!/usr/bin/env python3
"""Writes the generated list of every range and limit into docs/bad-input.md.

The section between the `limits:begin` and `limits:end` markers is replaced by the output of
`cellseq limits --markdown` (the test `ranges::bad_input_md_lists_every_range_as_limits_prints_it`
requires the two to be equal). Usage: scripts/update-limits.py [PATH-TO-cellseq]
(default: target/release/cellseq; build it first with `cargo build --release`).
"""
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "peers"))
import safe_files  # noqa: E402

root = pathlib.Path(__file__).resolve().parent.parent
binary = sys.argv[1] if len(sys.argv) > 1 else str(root / "target/release/cellseq")
section = subprocess.run(
    [binary, "limits", "--markdown"], check=True, capture_output=True, text=True
).stdout.rstrip("\n")
lines = section.splitlines()
begin, end = lines[0], lines[-1]
doc_path = root / "docs/bad-input.md"
doc = doc_path.read_text()
a, b = doc.find(begin), doc.find(end)
if a < 0 or b < 0:
    # first time: the section goes after the introduction, before the first `## ` heading
    at = doc.find("\n## ")
    doc = doc[: at + 1] + section + "\n\n" + doc[at + 1 :]
else:
    doc = doc[:a] + section + doc[b + len(end) :]
safe_files.write_text(doc_path, doc)
print(f"updated {doc_path.relative_to(root)} ({len(lines)} lines of limits)")
