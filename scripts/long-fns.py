#!/usr/bin/env python3
"""Lists the Rust functions longer than a limit (issue 27: no function over ~150 lines
without a stated reason).

usage: python3 scripts/long-fns.py [DIR ...] [--over N] [--top K] [--reasons]
  DIR       directories searched for *.rs (default: every crates/*/src)
  --over N  list functions with more than N lines (default 150)
  --top K   list the K longest functions instead, whatever their length
  --reasons also show the reason comment of a function kept long on purpose

A function's length counts the lines from its `fn` keyword to its closing brace, both
included (doc comments and attributes are not counted). A function kept long on purpose says
why in a comment starting with `// long:` on one of the three lines above its `fn` line (or
inside its doc comment block); such functions are listed with their reason and do not make the
exit status non-zero. Exit status: 1 when a function is over the limit without a reason.
"""
import os
import re
import sys

FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def blank_out(src):
    """The source with comments, strings and char literals replaced by spaces (newlines kept),
    so that braces and `fn` inside them are not counted."""
    out = list(src)
    i, n = 0, len(src)

    def blank(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            blank(i, j)
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            blank(i, j)
            i = j
        elif (c == "r" or src.startswith("br", i)) and re.match(r'b?r#*"', src[i:i + 40]) \
                and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            m = re.match(r'b?r(#*)"', src[i:])
            end = '"' + m.group(1)
            j = src.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            blank(i, j)
            i = j
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            blank(i, j + 1)
            i = j + 1
        elif c == "'":
            # a char literal ('x', '\n', '\u{..}') or a lifetime ('a)
            m = re.match(r"'(\\(u\{[0-9a-fA-F]+\}|x[0-9a-fA-F]{2}|.)|[^\\'])'", src[i:])
            if m:
                blank(i, i + m.end())
                i += m.end()
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def functions(path):
    """(name, first line, lines, reason) of every function with a body in a file."""
    src = open(path, encoding="utf-8").read()
    text = blank_out(src)
    raw_lines = src.split("\n")
    found = []
    for m in FN.finditer(text):
        # the body: the first `{` after the signature at bracket depth 0, unless `;` comes first
        depth, j = 0, m.end()
        while j < len(text):
            ch = text[j]
            if ch in "([<":
                depth += 1
            elif ch in ")]>" and depth > 0:
                # `->` is not a closing bracket
                if not (ch == ">" and text[j - 1] == "-"):
                    depth -= 1
            elif ch == ";" and depth == 0:
                j = -1
                break
            elif ch == "{" and depth == 0:
                break
            j += 1
        if j < 0 or j >= len(text):
            continue
        braces, k = 0, j
        while k < len(text):
            if text[k] == "{":
                braces += 1
            elif text[k] == "}":
                braces -= 1
                if braces == 0:
                    break
            k += 1
        first = text.count("\n", 0, m.start()) + 1
        last = text.count("\n", 0, k) + 1
        reason = None
        for ln in range(first - 2, max(first - 12, -1), -1):
            line = raw_lines[ln].strip()
            if line.startswith("// long:"):
                reason = line[len("// long:"):].strip()
                break
            if not (line.startswith("//") or line.startswith("#[")):
                break
        found.append((m.group(1), first, last - first + 1, reason))
    return found


def main(argv):
    dirs, over, top, reasons = [], 150, None, False
    it = iter(argv)
    for a in it:
        if a == "--over":
            over = int(next(it))
        elif a == "--top":
            top = int(next(it))
        elif a == "--reasons":
            reasons = True
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        else:
            dirs.append(a)
    rows = []
    default = sorted(os.path.join("crates", c, "src") for c in os.listdir("crates"))
    for d in dirs or default:
        for root, _, files in os.walk(d):
            for f in sorted(files):
                if f.endswith(".rs"):
                    p = os.path.join(root, f)
                    rows += [(n, p, name, first, why) for name, first, n, why in functions(p)]
    rows.sort(key=lambda r: (-r[0], r[1], r[3]))
    if top is not None:
        rows = rows[:top]
    else:
        rows = [r for r in rows if r[0] > over]
    bad = 0
    for n, p, name, first, why in rows:
        note = ""
        if why is not None:
            note = f"  (kept: {why})" if reasons else "  (kept, reason stated)"
        elif top is None:
            bad += 1
        print(f"{n:5d}  {p}:{first}  {name}{note}")
    if top is None:
        print(f"{len(rows)} function(s) over {over} lines, {bad} without a stated reason")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
