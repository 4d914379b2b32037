#!/usr/bin/env python3
"""The transport seam is closed (issue 9): adding a transport
edits no core file, and every input reaches its engine the same way.

Given the sources, when the core (daemon/core/, daemon/trajd.c) is read with
comments and strings blanked, then it names no transport and includes no
header of a transport family; no transport family includes another's header;
and transport_table[] is generated from the
`const transport_t NAME_transport = {` definitions of daemon/*/*_transport.c,
in path order, including one in a new file.
"""
import glob
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from csource import blank  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
GEN = os.path.join(ROOT, "daemon", "core", "transport_table.sh")
CORE = sorted(glob.glob(os.path.join(ROOT, "daemon", "core", "*.[ch]"))) + [
    os.path.join(ROOT, "daemon", "trajd.c")]
# The core's own names that end in _transport: the lookups of a transport's config block.
CORE_OWN = {"cfg_transport", "cfg_obj_transport"}
DEF = re.compile(r"^const transport_t (\w+_transport) = \{", re.M)


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def transport_files():
    return sorted(glob.glob(os.path.join(ROOT, "daemon", "*", "*_transport.c")))


def defined(files):
    return [name for f in files for name in DEF.findall(read(f))]


def generate(files):
    return subprocess.run(["sh", GEN] + files, capture_output=True, text=True, check=True).stdout


def table(text):
    body = text[text.index("transport_table[] = {"):]
    return re.findall(r"&(\w+),", body)


class Seam(unittest.TestCase):
    def test_core_names_no_transport(self):
        # a transport family: a folder holding a <name>_transport.c (daemon/ctl/,
        # the control socket, and daemon/tools/ are modules the core may call)
        families = {os.path.basename(os.path.dirname(f)) for f in transport_files()} - {"core"}
        self.assertTrue({"can", "modbus", "replay", "csv"} <= families, families)
        for path in CORE:
            raw = read(path)
            rel = os.path.relpath(path, ROOT)
            for inc in re.findall(r'^#include "([^"]+)"', raw, re.M):
                hits = glob.glob(os.path.join(ROOT, "daemon", "*", inc))
                for h in hits:
                    fam = os.path.basename(os.path.dirname(h))
                    self.assertNotIn(fam, families, f"{rel} includes {inc} of daemon/{fam}/")
            code = blank(raw)
            names = set(re.findall(r"\b(\w+_transport)\b", code)) - CORE_OWN
            self.assertEqual(names, set(), f"{rel} names transports")
            for word in ("OBJ_SRC", "stats_can", "STATS_CAN", "modbus", "replay"):
                self.assertFalse(word in code, f"{rel}: '{word}' outside comments")

    def test_no_transport_includes_another(self):
        # Given every source of a transport family (a folder holding a
        # <name>_transport.c), then none includes a header of another family:
        # what one transport shows of another (Modbus of the CAN bus and
        # drives) goes through the core (stats_t.bus, obj_t.drive).
        families = {os.path.basename(os.path.dirname(f)) for f in transport_files()} - {"core"}
        self.assertTrue({"can", "modbus"} <= families, families)
        breaches = []
        for fam in sorted(families):
            for path in sorted(glob.glob(os.path.join(ROOT, "daemon", fam, "*.[ch]")) +
                               glob.glob(os.path.join(ROOT, "daemon", fam, "*.cc"))):
                for inc in re.findall(r'^\s*#\s*include\s+"([^"]+)"', read(path), re.M):
                    for h in glob.glob(os.path.join(ROOT, "daemon", "*", inc)):
                        other = os.path.basename(os.path.dirname(h))
                        if other in families and other != fam:
                            breaches.append(f"{os.path.relpath(path, ROOT)} includes {inc} "
                                            f"of daemon/{other}/")
        self.assertEqual(breaches, [], "a transport includes another transport's header")

    def test_inputs_push_through_obj_push(self):
        # Given every transport file, then none offers waypoints to an engine
        # directly: the one push path is obj_push_from (replay included).
        for f in transport_files():
            code = blank(read(f))
            self.assertNotIn("engine_push(", code, f"{os.path.relpath(f, ROOT)}: use obj_push_from")
        self.assertRegex(blank(read(os.path.join(ROOT, "daemon", "replay", "replay_transport.c"))),
                         r"\bobj_push_from\(")

    def test_table_is_every_definition_in_path_order(self):
        files = transport_files()
        want = defined(files)
        self.assertIn("csv_transport", want)
        self.assertIn("stdout_transport", want)   # two in one file
        self.assertEqual(table(generate(files)), want)
        built = os.path.join(BUILD, "gen", "transport_table.c")
        self.assertTrue(os.path.exists(built), f"{built} not built (make all)")
        self.assertEqual(table(read(built)), want)

    def test_new_transport_file_is_picked_up(self):
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "aaa"))
            new = os.path.join(d, "aaa", "aaa_transport.c")
            with open(new, "w") as f:
                f.write("/* two here */\nconst transport_t aaa_transport = {\n};\n"
                        "static const transport_t not_a_definition_transport;\n"
                        "const transport_t bbb_transport = {\n};\n")
            got = table(generate([new] + transport_files()))
        self.assertEqual(got[:2], ["aaa_transport", "bbb_transport"])
        self.assertEqual(got[2:], defined(transport_files()))

    def test_generator_refuses_nothing_found(self):
        with tempfile.NamedTemporaryFile("w", suffix="_transport.c") as f:
            f.write("int x;\n")
            f.flush()
            r = subprocess.run(["sh", GEN, f.name], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("no 'const transport_t", r.stderr)


if __name__ == "__main__":
    unittest.main()
