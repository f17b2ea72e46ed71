#!/usr/bin/env python3
"""Run the command-line and Python blocks of docs/tutorial.md and compare what they print with the page.

A checked block is a ```sh or ```python block preceded by a marker line

    <!-- check: tol=1e-6 [quick] -->

and followed (after blank lines only) by the ```text block of its printed output. Every checked
block runs in page order in one temporary folder (so a later block can read what an earlier one
wrote). The commands of a ```sh block run with `gearbif` replaced by the binary given with --bin;
the ```python blocks run in one interpreter given with --python, one after the other in one
namespace, as a reader pastes them into one session (a later block uses the imports of an earlier
one). Blocks of a language whose runner is not given are skipped. stdout and stderr are taken
together, as a terminal shows them. The printed text and the page's text must agree
word for word, and every number within the block's relative tolerance `tol`; the elapsed-time
prefixes of progress lines ("[  12.3 s]") are ignored. `quick` marks the blocks cheap enough for
the test suite (tests/tutorial_docs.rs runs them with --quick).

Exit status 0 when every block agrees, 1 with a list of the differences otherwise.

    python3 scripts/check_tutorial.py --bin target/release/gearbif            # every checked block
    python3 scripts/check_tutorial.py --bin target/release/gearbif --quick    # the quick ones
    python3 scripts/check_tutorial.py --python PYTHON --quick                 # the quick Python ones
"""

import argparse
import json
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
        lang = lines[i].strip()[3:] if i < len(lines) else ""
        if lang not in ("sh", "python"):
            sys.exit(f"line {where}: a check marker must be followed by a ```sh or ```python block")
        body, i = fenced(lines, i)
        while i < len(lines) and not lines[i].strip():
            i += 1
        if i >= len(lines) or lines[i].strip() != "```text":
            sys.exit(f"line {where}: the checked ```{lang} block must be followed by a ```text block")
        text, i = fenced(lines, i)
        code = join_continuations(body) if lang == "sh" else "\n".join(body)
        out.append((where, opts, lang, code, "\n".join(text)))
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


# The Python session: reads one JSON string (a block's code) per line, runs it in one namespace
# and answers with one JSON string, what it printed (a traceback where it raised).
SESSION = r"""
import contextlib, io, json, sys, traceback
ns = {"__name__": "__main__"}
for line in sys.stdin:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        try:
            exec(compile(json.loads(line), "<block>", "exec"), ns)
        except Exception:
            traceback.print_exc(file=buf)
    sys.__stdout__.write(json.dumps(buf.getvalue()) + "\n")
    sys.__stdout__.flush()
"""


def run_sh(cmds, binary, cwd):
    """What the commands print (stdout and stderr), with the exit status of a failing one."""
    got = ""
    for c in cmds:
        argv = shlex.split(c)
        if argv and argv[0] == "gearbif":
            argv[0] = binary
        r = subprocess.run(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        got += r.stdout
        if r.returncode != 0:
            got += f"\n(exit status {r.returncode})"
    return got


def run_python(session, code):
    """What the block prints in the session."""
    session.stdin.write(json.dumps(code) + "\n")
    session.stdin.flush()
    return json.loads(session.stdout.readline())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", help="the gearbif binary that runs the command-line blocks")
    ap.add_argument("--python", help="the Python interpreter (with gearbif importable) that runs the Python blocks")
    ap.add_argument("--page", default=os.path.join(os.path.dirname(__file__), "..", "docs", "tutorial.md"))
    ap.add_argument("--quick", action="store_true", help="only the blocks marked quick")
    a = ap.parse_args()
    if not (a.bin or a.python):
        sys.exit("give --bin (the command-line blocks), --python (the Python blocks) or both")
    page = open(a.page, encoding="utf-8").read()
    runnable = {"sh": bool(a.bin), "python": bool(a.python)}
    todo = [b for b in blocks(page) if (b[1]["quick"] or not a.quick) and runnable[b[2]]]
    if not todo:
        sys.exit("no checked blocks found")
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        session = None
        if a.python:
            python = os.path.abspath(a.python) if os.sep in a.python else a.python
            session = subprocess.Popen(
                [python, "-c", SESSION], cwd=tmp, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
            )
        for where, opts, lang, code, expected in todo:
            if lang == "sh":
                got = run_sh(code, os.path.abspath(a.bin), tmp)
                title = " && ".join(code)
            else:
                got = run_python(session, code)
                title = "python: " + code.strip().split("\n")[0]
            bad = compare(expected, got, opts["tol"])
            status = "ok" if not bad else "DIFFERS"
            print(f"{a.page}:{where}: {title}: {status}")
            for b in bad[:10]:
                print("  " + b)
            failures += bool(bad)
        if session is not None:
            session.stdin.close()
            session.wait()
    if failures:
        print(f"{failures} of {len(todo)} checked blocks differ from the page")
        return 1
    print(f"all {len(todo)} checked blocks agree with the page")
    return 0


if __name__ == "__main__":
    sys.exit(main())
