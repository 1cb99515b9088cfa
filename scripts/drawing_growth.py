#!/usr/bin/env python3
"""Growth of `cellseq optimize` on generated drawings (issue 50): n random short lines in one
layer (`strokes`) and n/10 top-level groups of 10 lines (`groups`), n = 1e3, 1e4, 1e5, each run
once with a deterministic budget of 20 evaluations per stroke; wall time and peak memory from
/usr/bin/time. Not a timed test: compare the figures of one run side by side.

  cargo build --release && python3 scripts/drawing_growth.py [--cellseq target/release/cellseq]
"""
import argparse, os, random, subprocess, tempfile

def doc(body):
    return ('<svg xmlns="http://www.w3.org/2000/svg" width="1000mm" height="1000mm" '
            f'viewBox="0 0 1000 1000">\n{body}\n</svg>\n')

def strokes(n, r):
    return "\n".join(f'<path d="M{r.uniform(0, 990):.3f} {r.uniform(0, 990):.3f} '
                     f'l{r.uniform(-5, 5):.3f} {r.uniform(-5, 5):.3f}" stroke="black" fill="none"/>'
                     for _ in range(n))

def groups(n, r):
    out = []
    for g in range(n // 10):
        cx, cy = r.uniform(0, 980), r.uniform(0, 980)
        paths = "".join(f'<path d="M{cx + r.uniform(0, 15):.3f} {cy + r.uniform(0, 15):.3f} l3 1" '
                        'stroke="black" fill="none"/>' for _ in range(10))
        out.append(f'<g id="g{g}">{paths}</g>')
    return "\n".join(out)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cellseq", default="target/release/cellseq")
    a = ap.parse_args()
    print("| family | n | wall s | peak MB |\n|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as d:
        for name, make in (("strokes", strokes), ("groups", groups)):
            for n in (1_000, 10_000, 100_000):
                src = os.path.join(d, f"{name}{n}.svg")
                with open(src, "w") as f:
                    f.write(doc(make(n, random.Random(n))))
                r = subprocess.run(["/usr/bin/time", "-f", "%e %M", a.cellseq, "optimize", src,
                                    "-o", os.path.join(d, "out.svg"), "--max-evals", str(20 * n)],
                                   capture_output=True, text=True, check=True)
                wall, kb = r.stderr.strip().splitlines()[-1].split()
                print(f"| {name} | {n} | {float(wall):.2f} | {int(kb) / 1024:.0f} |")

if __name__ == "__main__":
    main()
