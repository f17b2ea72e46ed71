#!/usr/bin/env python3
"""Write the Python API reference (docs/python-api.md) from the package's docstrings.

    PYTHONPATH=target/python-ext target/python-venv/bin/python scripts/python_api_doc.py

Every public name of the package, by the groups of `gearbif._GROUPS` (which make its `__all__`),
with its signature and docstring; for a class its
public methods and properties too. python/tests/test_api_doc.py checks that the page is what this
script writes now, so a changed docstring or signature without a regenerated page fails the tests.
"""

import argparse
import inspect
import os

import gearbif

HEADER = """# Python API reference

Generated from the docstrings by `scripts/python_api_doc.py` (do not edit by hand). Units: t [s],
f [Hz], β [rad], ω [rad/s] (states on the lift); shaft angles in degrees where the argument name
ends in `_deg`. The tutorial ([tutorial.md](tutorial.md)) shows the package at work; the dicts of
the results are described in [formats.md](formats.md).
"""



def signature(obj):
    try:
        return str(inspect.signature(obj))
    except (TypeError, ValueError):
        return "(…)"


def doc(obj):
    d = inspect.getdoc(obj) or ""
    return d.strip()


def members(cls):
    """(name, kind, object) of the public methods and properties a user calls."""
    out = []
    for name, obj in sorted(vars(cls).items()):
        if name.startswith("_"):
            continue
        if isinstance(obj, (staticmethod, classmethod)):
            out.append((name, "method", getattr(cls, name)))
        elif inspect.isdatadescriptor(obj) or isinstance(obj, property):
            out.append((name, "property", obj))
        elif callable(obj):
            out.append((name, "method", obj))
    return out


def render():
    lines = [HEADER]
    for title, names in gearbif._GROUPS.items():
        lines.append(f"## {title}\n")
        for name in names:
            obj = getattr(gearbif, name)
            if inspect.isclass(obj):
                bases = [b.__name__ for b in obj.__bases__ if b is not object]
                base = f"({', '.join(bases)})" if issubclass(obj, BaseException) else signature(obj)
                lines.append(f"### `{name}{base}`\n")
                if doc(obj):
                    lines.append(doc(obj) + "\n")
                if issubclass(obj, BaseException):
                    continue
                for mname, kind, m in members(obj):
                    sig = "" if kind == "property" else signature(m)
                    first = doc(m).split("\n\n")[0].replace("\n", " ")
                    lines.append(f"- `{mname}{sig}`{' (property)' if kind == 'property' else ''}: {first}")
                lines.append("")
            else:
                lines.append(f"### `{name}{signature(obj)}`\n")
                lines.append(doc(obj) + "\n")
    return "\n".join(lines).rstrip() + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "python-api.md"))
    a = ap.parse_args()
    with open(a.out, "w", encoding="utf-8") as f:
        f.write(render())
    print("wrote", a.out)


if __name__ == "__main__":
    main()
