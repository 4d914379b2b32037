#!/usr/bin/env python3
"""The C tests share one helper header (issue 9).

Given tests/unit/*.c, tests/bench/*.c and tests/fuzz/*.c, then none includes
cmocka.h itself (tests/helpers/test.h does, with what it needs first), and
no function of more than one statement is defined with the same body in two
of them: a helper copied between tests belongs in tests/helpers/test.h.  A
one-statement forwarding wrapper (e.g. a file's parse() around track_load_text)
may repeat: sharing it would tie test.h to that module's header.
"""
import collections
import glob
import os
import re
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from csource import blank, functions  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
FILES = sorted(glob.glob(os.path.join(ROOT, "tests", d, "*.c")) for d in ("unit", "bench", "fuzz"))
FILES = [f for group in FILES for f in group]
# The entry points every program or fuzz target defines by contract.
ENTRY = {"main", "LLVMFuzzerTestOneInput", "LLVMFuzzerInitialize"}


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


class SharedHelpers(unittest.TestCase):
    def test_cmocka_only_through_test_h(self):
        for f in FILES:
            self.assertNotRegex(read(f), r"#include <cmocka\.h>",
                                f"{os.path.relpath(f, ROOT)}: #include \"test.h\" instead")

    def test_no_helper_copied_between_files(self):
        seen = collections.defaultdict(list)
        for f in FILES:
            lines = blank(read(f)).split("\n")
            for name, a, b in functions(f):
                if name in ENTRY:
                    continue
                body = re.sub(r"\s+", " ", " ".join(lines[a - 1:b])).strip()
                if body[body.index("{"):].count(";") < 2:
                    continue  # a one-statement wrapper
                seen[body].append(f"{os.path.relpath(f, ROOT)}:{a} {name}()")
        copies = [where for where in seen.values()
                  if len({w.split(":")[0] for w in where}) > 1]
        self.assertEqual(copies, [], "the same function in several test files: "
                         "move it to tests/helpers/test.h")


if __name__ == "__main__":
    unittest.main()
