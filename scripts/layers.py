#!/usr/bin/env python3
"""Checks that every import follows the layers of ARCHITECTURE.md (CI runs it beside the
long-function check).

usage: python3 scripts/layers.py [--graph]
  --graph   print every module-to-module import found, then check

Three rules, each failing the run with the file and line of the offending import:

1. Crates: a workspace crate depends only on the crates below it (CRATES), and the core's
   dependency tree holds none of the crates it must stay free of (CORE_FORBIDDEN: plotting,
   PDF, CAD, XML and command-line crates) -- checked with `cargo tree` when cargo is on PATH.
2. Modules inside a crate: a module imports only modules of a lower rank (LAYERS; modules of the
   same rank may not import each other either, unless listed in SAME_RANK_OK).
3. Codecs run no solver: the G-code, SVG, DXF and drawing modules of cellseq-programs import
   nothing of the core's solving API (CODEC_FORBIDDEN).
4. Examples are what a newcomer copies: they use the public API only, none of the modules the
   `internals` feature opens (CORE_INTERNAL).

An import is a `crate::x` or `<crate>::x` path outside comments and outside test code (a
`#[cfg(test)]` module, or a file declared only as a test module). Exit status 1 on any breach.
"""
import os
import re
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

# Workspace crates and the workspace crates each may depend on.
CRATES = {
    "cellseq": [],
    "cellseq-programs": ["cellseq"],
    "cellseq-lab": ["cellseq", "cellseq-programs"],
    "cellseq-cli": ["cellseq", "cellseq-programs", "cellseq-lab"],
    "cellseq-py": ["cellseq", "cellseq-programs", "cellseq-lab"],
}

# Crates the core's (normal) dependency tree must not contain.
CORE_FORBIDDEN = [
    "plotters", "svg2pdf", "resvg", "usvg", "dxf", "roxmltree", "kurbo", "svgtypes",
    "clap", "anyhow", "indicatif", "statrs", "chrono", "walkdir", "globset", "png",
]

# Module ranks per crate, lowest first: a module may import modules of lower rank only.
LAYERS = {
    "cellseq": [
        ["error", "clock"],
        ["files", "geom", "params"],
        ["precedence"],
        ["model"],
        ["validate", "checker", "formats"],
        ["cost", "generate"],
        ["bound"],
        ["context"],
        ["engine"],
        ["construct"],
        ["solvers"],
        ["solve"],
        ["prelude", "lib"],
    ],
    "cellseq-programs": [
        ["drawing", "units"],
        ["gcode", "svg", "dxf"],
        ["optimize"],
        ["job"],
        ["api"],
        ["lib"],
    ],
    "cellseq-lab": [
        ["hash", "stats", "provenance", "layers", "estimate"],
        ["plan", "manifest", "results"],
        ["run", "plot"],
        ["figures", "paper", "latex"],
        ["report"],
        ["lib"],
    ],
    "cellseq-cli": [
        ["cli"],
        ["main"],
    ],
    "cellseq-py": [
        ["errors"],
        ["convert"],
        ["run", "instance"],
        ["info"],
        ["solve", "paths", "programs", "lab"],
        ["lib"],
    ],
}

# Same-rank imports allowed: (importer, imported).
SAME_RANK_OK = {
    ("cellseq", "formats", "validate"),
    ("cellseq", "formats", "checker"),
    ("cellseq", "generate", "cost"),
    ("cellseq-programs", "svg", "dxf"),
    ("cellseq-programs", "dxf", "gcode"),
    ("cellseq-lab", "report", "latex"),
    ("cellseq-lab", "latex", "report"),
    ("cellseq-lab", "figures", "paper"),
}

# The core's modules that are public only with the `internals` feature.
CORE_INTERNAL = {"bound", "construct", "context", "cost", "engine", "solvers"}

# What the codecs of cellseq-programs must not import from the core.
CODEC_MODULES = {"gcode", "svg", "dxf", "drawing", "units"}
CODEC_FORBIDDEN = {"solvers", "solve", "bound", "search"}


def strip(text):
    """The text with comments and `#[cfg(test)]` items removed (line numbers kept)."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    out = []
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.strip().startswith("#[cfg(test)]"):
            # skip the attribute and the item after it (a `mod x;` or a braced block)
            depth = 0
            seen = False
            j = i + 1
            while j < len(lines):
                depth += lines[j].count("{") - lines[j].count("}")
                seen = seen or "{" in lines[j]
                done = (seen and depth <= 0) or (not seen and lines[j].rstrip().endswith(";"))
                out.append("")
                j += 1
                if done:
                    break
            out.append("")
            i = j
            continue
        out.append(line)
        i += 1
    return "\n".join(out)


def test_only_files(src):
    """Files declared only as test modules (`#[cfg(test)] mod x;`, `#[path]` or not)."""
    skip = set()
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            p = os.path.join(root, f)
            text = open(p, encoding="utf-8").read()
            for m in re.finditer(r"#\[cfg\(test\)\]\s*(?:#\[path\s*=\s*\"([^\"]+)\"\]\s*)?mod\s+(\w+)\s*;", text):
                base = os.path.dirname(p)
                if f not in ("mod.rs", "lib.rs", "main.rs"):
                    base = os.path.join(base, f[:-3])
                if m.group(1):
                    skip.add(os.path.normpath(os.path.join(os.path.dirname(p), m.group(1))))
                else:
                    skip.add(os.path.normpath(os.path.join(base, m.group(2) + ".rs")))
                    skip.add(os.path.normpath(os.path.join(base, m.group(2), "mod.rs")))
    return skip


def module_of(src, path):
    rel = os.path.relpath(path, src)
    top = rel.split(os.sep)[0]
    return top[:-3] if top.endswith(".rs") else top


def rank_of(crate, module):
    for r, names in enumerate(LAYERS[crate]):
        if module in names:
            return r
    return None


def check_modules(crate, graph):
    src = os.path.join(ROOT, "crates", crate, "src")
    skip = test_only_files(src)
    lib_name = crate.replace("-", "_")
    ws = {c.replace("-", "_"): c for c in CRATES}
    bad = []
    for root, _, files in os.walk(src):
        for f in sorted(files):
            if not f.endswith(".rs"):
                continue
            p = os.path.normpath(os.path.join(root, f))
            if p in skip:
                continue
            me = module_of(src, p)
            mine = rank_of(crate, me)
            if mine is None:
                bad.append(f"{os.path.relpath(p, ROOT)}: module `{me}` has no layer in scripts/layers.py")
                continue
            text = strip(open(p, encoding="utf-8").read())
            for n, line in enumerate(text.split("\n"), 1):
                for m in re.finditer(r"\b(crate|%s)::(?:\{\s*)?([a-z_]+)" % "|".join(ws), line):
                    owner, target = m.group(1), m.group(2)
                    if owner in ("crate", lib_name):
                        if target == me:
                            continue
                        graph.add((crate, me, target))
                        theirs = rank_of(crate, target)
                        if theirs is None:
                            continue  # a re-exported item at the root (crate::Error), not a module
                        if theirs > mine or (theirs == mine and (crate, me, target) not in SAME_RANK_OK):
                            bad.append(f"{os.path.relpath(p, ROOT)}:{n}: `{me}` imports `{target}`, "
                                       f"which is not below it in {crate}'s layers")
                    else:
                        other = ws[owner]
                        graph.add((crate, me, f"{other}::{target}"))
                        if other not in CRATES[crate] and other != crate:
                            bad.append(f"{os.path.relpath(p, ROOT)}:{n}: {crate} imports {other}")
                        if crate == "cellseq-programs" and me in CODEC_MODULES \
                                and other == "cellseq" and target in CODEC_FORBIDDEN:
                            bad.append(f"{os.path.relpath(p, ROOT)}:{n}: the codec `{me}` imports "
                                       f"cellseq::{target}: codecs run no solver")
    return bad


def check_examples():
    bad = []
    for crate in CRATES:
        ex = os.path.join(ROOT, "crates", crate, "examples")
        if not os.path.isdir(ex):
            continue
        for f in sorted(os.listdir(ex)):
            if not f.endswith(".rs"):
                continue
            p = os.path.join(ex, f)
            text = strip(open(p, encoding="utf-8").read())
            for n, line in enumerate(text.split("\n"), 1):
                for m in re.finditer(r"\bcellseq::([a-z_]+)", line):
                    if m.group(1) in CORE_INTERNAL:
                        bad.append(f"{os.path.relpath(p, ROOT)}:{n}: the example uses the "
                                   f"internal module cellseq::{m.group(1)}")
    return bad


def check_manifests():
    bad = []
    for crate, allowed in CRATES.items():
        toml = os.path.join(ROOT, "crates", crate, "Cargo.toml")
        text = open(toml, encoding="utf-8").read()
        deps = re.search(r"^\[dependencies\]\n(.*?)(?=^\[|\Z)", text, flags=re.S | re.M)
        for line in (deps.group(1).splitlines() if deps else []):
            name = re.match(r"\s*([A-Za-z0-9_-]+)", line)
            if name and name.group(1) in CRATES and name.group(1) not in allowed:
                bad.append(f"crates/{crate}/Cargo.toml: depends on {name.group(1)}")
    return bad


def check_core_tree():
    try:
        out = subprocess.run(
            ["cargo", "tree", "-p", "cellseq", "-e", "normal", "--prefix", "none"],
            cwd=ROOT, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"note: cargo tree not run ({e}); crate-tree rule skipped", file=sys.stderr)
        return []
    names = {l.split()[0] for l in out.splitlines() if l.strip()}
    return [f"the core crate `cellseq` depends on `{n}` (not allowed: see CORE_FORBIDDEN)"
            for n in sorted(names & set(CORE_FORBIDDEN))]


def main(argv):
    graph = set()
    bad = check_manifests()
    for crate in CRATES:
        bad += check_modules(crate, graph)
    bad += check_examples()
    bad += check_core_tree()
    if "--graph" in argv:
        for c, a, b in sorted(graph):
            print(f"{c}: {a} -> {b}")
    for b in bad:
        print(b)
    print(f"{len(bad)} import(s) against the layers")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
