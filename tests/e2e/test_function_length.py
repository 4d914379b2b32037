#!/usr/bin/env python3
"""Functions in daemon/ over MAX_LINES lines fail this test unless allow-listed.

Issue 9: no function over ~80 lines in daemon/ unless argued
for.  A function's length is counted from the line holding its name to its
closing brace.  The scanner is a small brace matcher over the source with
comments, strings and character constants blanked (no compiler needed); a
definition is a '{' at file scope that follows a ')' (so struct, enum and
array initialisers are not functions).

    python3 tests/e2e/test_function_length.py          # check
    python3 tests/e2e/test_function_length.py --list   # every function, longest first

Limit of the scanner: a function defined by a macro, or with braces inside
#if branches that do not balance, is measured wrongly; none in daemon/ is.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from csource import functions  # noqa: E402

MAX_LINES = 80

# file:function -> why it stays long.  Each entry is argued; an entry that no
# longer matches a function over MAX_LINES fails the test, so the list cannot
# go stale.
ALLOW = {
}


ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def scan():
    rows = []
    for d, _, files in sorted(os.walk(os.path.join(ROOT, "daemon"))):
        for f in sorted(files):
            if not f.endswith(".c"):
                continue
            rel = os.path.relpath(os.path.join(d, f), ROOT)
            for name, a, b in functions(os.path.join(d, f)):
                rows.append((b - a + 1, rel, name, a))
    return rows


def main():
    rows = scan()
    if "--list" in sys.argv:
        for n, rel, name, a in sorted(rows, reverse=True):
            print(f"{n:5d} {rel}:{a} {name}")
        return 0
    bad, used = [], set()
    for n, rel, name, a in rows:
        if n <= MAX_LINES:
            continue
        key = f"{rel}:{name}"
        if key in ALLOW:
            used.add(key)
            continue
        bad.append(f"{rel}:{a}: {name}() is {n} lines (max {MAX_LINES}): split it, or argue "
                   f"for it in ALLOW in {os.path.relpath(__file__, ROOT)}")
    for key in sorted(set(ALLOW) - used):
        bad.append(f"{key}: allow-listed but not over {MAX_LINES} lines (or gone): remove the entry")
    nfun = len(rows)
    longest = max(rows)[0] if rows else 0
    for b in bad:
        print(b)
    print(f"{nfun} functions in daemon/, longest {longest} lines, {len(ALLOW)} allowed over "
          f"{MAX_LINES}, {len(bad)} problem(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
