#!/usr/bin/env python3
"""Run the command-line blocks of docs/tutorial.md and compare what they print with the page.

A checked block is a ```sh block preceded by a marker line

    <!-- check: tol=1e-6 [quick] -->

and followed (after blank lines only) by the ```text block of its printed output. The commands of
every checked block run in order in one temporary folder (so a later block can read what an
earlier one wrote), with `gearbif` replaced by the binary given with --bin; their stdout and stderr
are taken together, as a terminal shows them. The printed text and the page's text must agree
word for word, and every number within the block's relative tolerance `tol`; the elapsed-time
prefixes of progress lines ("[  12.3 s]") are ignored. `quick` marks the blocks cheap enough for
the test suite (tests/tutorial_docs.rs runs them with --quick).

Exit status 0 when every block agrees, 1 with a list of the differences otherwise.

    python3 scripts/check_tutorial.py --bin target/release/gearbif            # every checked block
    python3 scripts/check_tutorial.py --bin target/release/gearbif --quick    # the quick ones
"""

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile

MARKER = re.compile(r"^<!--\s*check:(.*)-->\s*$")
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
TIME_PREFIX = re.compile(r"^\[\s*[0-9.]+ s\]", re.M)


def blocks(page):
    """The checked blocks of the page: (line number, options, commands, expected text)."""
    lines = page.split("\n")
    out = []
    i = 0
    while i < len(lines):
        m = MARKER.match(lines[i])
        if not m:
            i += 1
            continue
        where = i + 1
        opts = dict(tol=0.0, quick=False)
        for word in m.group(1).split():
            if word == "quick":
                opts["quick"] = True
            elif word.startswith("tol="):
                opts["tol"] = float(word[4:])
            else:
                sys.exit(f"line {where}: unknown check option {word!r}")
        i += 1
        if i >= len(lines) or lines[i].strip() != "```sh":
            sys.exit(f"line {where}: a check marker must be followed by a ```sh block")
        cmds, i = fenced(lines, i)
        while i < len(lines) and not lines[i].strip():
            i += 1
        if i >= len(lines) or lines[i].strip() != "```text":
            sys.exit(f"line {where}: the checked ```sh block must be followed by a ```text block")
        text, i = fenced(lines, i)
        out.append((where, opts, join_continuations(cmds), "\n".join(text)))
    return out


def fenced(lines, i):
    """The lines inside the fenced block opening at line i, and the index after its end."""
    j = i + 1
    while j < len(lines) and lines[j].strip() != "```":
        j += 1
    return lines[i + 1 : j], j + 1


def join_continuations(cmds):
    out, cur = [], ""
    for c in cmds:
        if c.rstrip().endswith("\\"):
            cur += c.rstrip()[:-1] + " "
        else:
            cur += c
            if cur.strip() and not cur.strip().startswith("#"):
                out.append(cur.split(" #")[0].strip())
            cur = ""
    return out


def skeleton(text):
    """The text with its numbers taken out, and the numbers, whitespace collapsed."""
    text = TIME_PREFIX.sub("[T]", text.strip())
    nums = [float(n) for n in NUMBER.findall(text)]
    words = " ".join(NUMBER.sub("#", text).split())
    return words, nums


def compare(expected, got, tol):
    we, ne = skeleton(expected)
    wg, ng = skeleton(got)
    if we != wg or len(ne) != len(ng):
        # the first line that differs, for the message
        el = [skeleton(l)[0] for l in expected.strip().split("\n")]
        gl = [skeleton(l)[0] for l in got.strip().split("\n")]
        for k, (a, b) in enumerate(zip(el, gl)):
            if a != b:
                return [f"output line {k + 1} differs in its words:\n    page: {a}\n    now:  {b}"]
        return [f"the page shows {len(el)} lines, the command printed {len(gl)}"]
    bad = []
    for k, (a, b) in enumerate(zip(ne, ng)):
        if abs(a - b) > tol * max(abs(a), abs(b)):
            bad.append(f"number {k + 1}: page {a!r}, now {b!r} (tolerance {tol:g} relative)")
    return bad


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", required=True, help="the gearbif binary to run")
    ap.add_argument("--page", default=os.path.join(os.path.dirname(__file__), "..", "docs", "tutorial.md"))
    ap.add_argument("--quick", action="store_true", help="only the blocks marked quick")
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    page = open(a.page, encoding="utf-8").read()
    todo = [b for b in blocks(page) if b[1]["quick"] or not a.quick]
    if not todo:
        sys.exit("no checked blocks found")
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        for where, opts, cmds, expected in todo:
            got = ""
            for c in cmds:
                argv = shlex.split(c)
                if argv and argv[0] == "gearbif":
                    argv[0] = binary
                r = subprocess.run(argv, cwd=tmp, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                got += r.stdout
                if r.returncode != 0:
                    got += f"\n(exit status {r.returncode})"
            bad = compare(expected, got, opts["tol"])
            status = "ok" if not bad else "DIFFERS"
            print(f"{a.page}:{where}: {' && '.join(cmds)}: {status}")
            for b in bad[:10]:
                print("  " + b)
            failures += bool(bad)
    if failures:
        print(f"{failures} of {len(todo)} checked blocks differ from the page")
        return 1
    print(f"all {len(todo)} checked blocks agree with the page")
    return 0


if __name__ == "__main__":
    sys.exit(main())
