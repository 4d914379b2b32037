#!/usr/bin/python3
"""test_readme.py - the front page stays true: every path it names exists,
every module of lib/ and daemon/ is in its module -> tests table, and every
test that table names exists."""
import glob
import os
import re
import sys
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def readme():
    with open(os.path.join(ROOT, "README.md")) as f:
        return f.read()


class TestReadme(unittest.TestCase):
    def test_every_named_path_exists(self):
        # Given every `path` in backquotes that starts with a top-level folder,
        text = readme()
        paths = set(re.findall(r"`((?:lib|daemon|config|tests|systemd)/[^`\s]*)`", text))
        self.assertGreater(len(paths), 20)
        missing = []
        for p in paths:
            p = p.rstrip("/")
            if re.search(r"[<>|]|_X\b", p):
                continue  # a template such as daemon/<family>/<name>_transport.c
            # `lib/engine/engine.h` or `tests/*/test_X.py`-style patterns
            if not glob.glob(os.path.join(ROOT, p)):
                missing.append(p)
        # then each one is in the repository.
        self.assertEqual(missing, [], "README names paths that do not exist")

    def test_module_table_covers_every_module(self):
        text = readme()
        block = text.split("<!-- modules:begin -->")[1].split("<!-- modules:end -->")[0]
        rows = [l for l in block.splitlines() if l.startswith("| `")]
        named = {}
        for r in rows:
            cells = [c.strip() for c in r.strip("|").split("|")]
            named[cells[0].strip("`")] = cells[1]
        modules = sorted(os.path.relpath(p, ROOT) for p in
                         glob.glob(os.path.join(ROOT, "lib", "*", "*.c")) +
                         glob.glob(os.path.join(ROOT, "daemon", "*", "*.c")))
        self.assertEqual([m for m in modules if m not in named], [],
                         "modules missing from the README's module table")
        for mod, tests in named.items():
            self.assertTrue(os.path.exists(os.path.join(ROOT, mod)), mod)
            for t in re.findall(r"`([^`]+)`", tests):
                hits = glob.glob(os.path.join(ROOT, "tests", "*", t + "*"))
                self.assertTrue(hits, "%s: test %s does not exist" % (mod, t))


if __name__ == "__main__":
    unittest.main(verbosity=2)
