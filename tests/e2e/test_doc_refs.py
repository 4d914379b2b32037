"""test_doc_refs.py - what the documents cite, the code has; and what the code
has, the documents say (issue 29 item 3).  Each check asks the programs
themselves, not a list kept here:

1. config keys.  Every key config/trajd.conf documents (`key = value`,
   commented or indented, and `can.a, can.b` lists) in its section is
   accepted by `trajd --check-config` there (any verdict but "unknown key");
   every `section.key` and `key = value` cited in backticks in README.md,
   config/PROTOCOL.md and daemon/REFERENCE.md is such a key.  Back: every string
   literal of the daemon's and the engine's sources that trajd accepts as a
   key in some section is documented in trajd.conf (a key `..._x` documents
   its `_y` and `_z`).
2. command-line options.  Every `--option` the man pages, README.md and
   daemon/REFERENCE.md cite is in some program's --help; every option of a
   program's --help is in its man page.
3. setpoint flags.  Every ENGINE_SP_* bit of lib/motion.h is in
   config/PROTOCOL.md's flags table, and every bit the table names exists.
4. error codes.  Every engine_error_t code of lib/motion.h is in the DBC's
   ST_LastErr value table and in PROTOCOL.md's STATUS last-error list.
5. paths.  Every repository path README.md, config/PROTOCOL.md,
   daemon/REFERENCE.md, lib/engine/DESIGN.md and the folders' README.md files
   cite exists.
(Modbus registers: tests/e2e/test_mbmap_readme.sh; CAN ids and layouts: the
DBC, test_canproto.py.)
"""
import glob
import os
import re
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
BIN = os.path.join(BUILD, "bin")
TRAJD = os.path.join(BIN, "trajd")
TRACK = os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.csv")
DOCS = [os.path.join(ROOT, p) for p in ("README.md", "config/PROTOCOL.md", "daemon/REFERENCE.md")]
SECTIONS = ("daemon", "realtime", "modbus", "can")
PREFIXES = ("", "csv.", "replay.", "can.", "modbus.")


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


class Checker:
    """trajd --check-config on a small valid config with one line added."""

    def __init__(self, tmp):
        self.tmp = tmp
        self.n = 0

    def base(self, section, prefix):
        d = self.tmp
        obj = {"": "input = replay\nreplay.track = %s\noutput = stdout\n" % TRACK,
               "replay.": "input = replay\nreplay.track = %s\noutput = stdout\n" % TRACK,
               "csv.": "input = replay\nreplay.track = %s\noutput = csv\ncsv.path = %s/o.csv\n"
                       % (TRACK, d),
               "can.": "input = replay\nreplay.track = %s\noutput = can\n" % TRACK,
               "modbus.": "input = modbus\n"}[prefix]
        sec = {s: "" for s in SECTIONS}
        if prefix == "can.":
            sec["can"] = "log_out = %s/o.log\n" % d
        if prefix == "modbus.":
            sec["modbus"] = "writes = yes\nport = 0\n"
        return sec, obj

    def accepts(self, section, prefix, key, value="1"):
        """None if trajd knows key there, else its message."""
        sec, obj = self.base(section, prefix)
        line = "%s%s = %s\n" % (prefix, key, value)
        if section == "object":
            obj += line
        else:
            sec[section] += line
        text = "".join("[%s]\n%s" % (s, sec[s]) for s in SECTIONS if sec[s] or s == section)
        text += "[object.a]\nid = 0\n" + obj
        self.n += 1
        path = os.path.join(self.tmp, "c%d.conf" % self.n)
        with open(path, "w") as f:
            f.write(text)
        p = subprocess.run([TRAJD, "--check-config", path], capture_output=True, text=True, timeout=30)
        msg = p.stderr.strip()
        if "unknown key" in msg or "which this object does not use" in msg:
            return msg
        return None


def documented_keys():
    """{(section, key): value} from config/trajd.conf, sections as written
    ([object.NAME] -> object)."""
    out = {}
    section = None
    for line in read(os.path.join(ROOT, "config", "trajd.conf")).splitlines():
        m = re.match(r"^\[(\w+)(?:\.[\w-]+)?\]", line)
        if m:
            section = m.group(1)
            continue
        if section is None:
            continue
        m = re.match(r"^#?\s*([a-z][a-z0-9_]*(?:\.[a-z0-9_]+)?) =(?: (.*))?$", line)
        if m:
            out[(section, m.group(1))] = (m.group(2) or "").split("  ")[0].strip()
            continue
        m = re.match(r"^#\s+((?:can|csv|modbus|replay)\.[a-z0-9_]+(?:, (?:can|csv|modbus|replay)\.[a-z0-9_]+)+)",
                     line)
        if m:
            for k in m.group(1).split(", "):
                out.setdefault((section, k), "")
    return out


def code_literals():
    """String literals that could be keys, from the sources that parse the config."""
    files = glob.glob(os.path.join(ROOT, "daemon", "*", "*.c")) + \
        [os.path.join(ROOT, "lib", "engine", "engine_settings.c")]
    lits = set()
    for f in files:
        for line in read(f).splitlines():
            if not re.search(r"strcmp|strncmp|\bS\(|\{\s*\"|key", line):
                continue
            lits.update(re.findall(r"\"([a-z][a-z0-9_]{1,40})\"", line))
    return lits


def split_prefix(key):
    for p in PREFIXES[1:]:
        if key.startswith(p):
            return p, key[len(p):]
    return "", key


class DocRefs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmpd = tempfile.TemporaryDirectory()
        cls.chk = Checker(cls.tmpd.name)
        cls.doc = documented_keys()

    @classmethod
    def tearDownClass(cls):
        cls.tmpd.cleanup()

    def test_documented_keys_exist(self):
        self.assertGreater(len(self.doc), 80)
        bad = []
        for (section, key), value in sorted(self.doc.items()):
            prefix, name = split_prefix(key)
            msg = self.chk.accepts(section, prefix, name, value or "1")
            if msg:
                bad.append("[%s] %s: %s" % (section, key, msg))
        self.assertEqual(bad, [], "keys trajd.conf documents that trajd does not know")

    def test_code_keys_documented(self):
        have = {k for (_, k) in self.doc}
        for k in list(have):   # a per-axis key documented as _x stands for _y and _z
            if k.endswith("_x"):
                have.update({k[:-2] + "_y", k[:-2] + "_z"})
        missing = []
        for lit in sorted(code_literals()):
            for section in SECTIONS + ("object",):
                for prefix in (PREFIXES if section == "object" else ("",)):
                    key = prefix + lit
                    if self.chk.accepts(section, prefix, lit) is None and key not in have:
                        missing.append("[%s] %s" % (section, key))
        self.assertEqual(missing, [], "keys trajd accepts that config/trajd.conf does not document")

    def test_keys_cited_in_markdown(self):
        have = {k for (_, k) in self.doc}
        bad = []
        for path in DOCS:
            for m in re.finditer(r"`(?:\[[a-z]+\] )?((?:can|csv|modbus|replay)\.[a-z0-9_]+)(?: = [^`]*)?`",
                                 read(path)):
                k = m.group(1)
                base = re.sub(r"_[xyz]$", "_x", k)
                if k not in have and base not in have and not k.endswith("_") and "*" not in k:
                    bad.append("%s: %s" % (os.path.relpath(path, ROOT), k))
        self.assertEqual(sorted(set(bad)), [], "keys cited in the documents that trajd.conf lacks")


class Options(unittest.TestCase):
    def helps(self):
        out = {}
        for b in sorted(glob.glob(os.path.join(BIN, "*"))):
            p = subprocess.run([b, "--help"], capture_output=True, text=True, timeout=30)
            out[os.path.basename(b)] = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", p.stdout))
        return out

    def test_cited_options_exist(self):
        helps = self.helps()
        every = set().union(*helps.values())
        bad = []
        for path in DOCS + glob.glob(os.path.join(ROOT, "daemon", "doc", "*.[1-8]")):
            man = not path.endswith(".md")
            for line in read(path).replace("\\-", "-").splitlines():
                # in the Markdown files, options of our programs: on a line that names one
                # (or an options table row), not on a line of another command's
                if not man and not line.startswith("| `--") and (
                        not re.search(r"\btraj(d|replay|surf|ctl)\b", line)
                        or re.search(r"python3|systemctl|systemd-analyze|mbpoll|\bmake\b|\bbash\b|\.py\b", line)):
                    continue
                for o in set(re.findall(r"(?<![\w/-])(--[a-z][a-z0-9-]*)", line)):
                    if o not in every:
                        bad.append("%s: %s" % (os.path.relpath(path, ROOT), o))
        self.assertEqual(sorted(set(bad)), [], "options the documents cite that no program has")

    def test_options_in_man_pages(self):
        bad = []
        for prog, opts in self.helps().items():
            man = glob.glob(os.path.join(BUILD, "man", prog + ".[1-8]"))  # as built (and installed)
            self.assertTrue(man, "no man page for " + prog)
            text = read(man[0]).replace("\\-", "-")
            bad += ["%s: %s" % (prog, o) for o in sorted(opts) if o not in text]
        self.maxDiff = None
        self.assertEqual(bad, [], "options of --help missing from the man page")


class FlagsAndErrors(unittest.TestCase):
    def test_flags_table(self):
        motion = read(os.path.join(ROOT, "lib", "motion.h"))
        bits = {int(v, 16): n for n, v in re.findall(r"#define ENGINE_SP_(\w+)\s+(0x[0-9a-fA-F]+)u", motion)}
        self.assertGreater(len(bits), 5)
        proto = read(os.path.join(ROOT, "config", "PROTOCOL.md"))
        m = re.search(r"\*\*Setpoint flags\*\*.*?\n\n((?:\|[^\n]*\n)+)", proto, re.S)
        self.assertIsNotNone(m, "PROTOCOL.md has no 'Setpoint flags' table")
        rows = {}
        for line in m.group(1).splitlines()[2:]:
            cells = [c.strip() for c in line.strip("|").split("|")]
            rows[int(cells[0], 0)] = cells[1]
        self.assertEqual(sorted(rows), sorted(bits), "flag bits: the table against motion.h")
        for v, n in bits.items():
            self.assertIn("ENGINE_SP_" + n, rows[v], "bit 0x%x" % v)

    def test_error_codes(self):
        motion = read(os.path.join(ROOT, "lib", "motion.h"))
        codes = {int(v): n for n, v in re.findall(r"\bENGINE_(E\w+)\s*=\s*(\d+)", motion)}
        self.assertGreater(len(codes), 10)
        dbc = read(os.path.join(ROOT, "config", "trajd.dbc"))
        table = re.search(r"VAL_ \d+ ST_LastErr (.*?);", dbc).group(1)
        have = {int(v) for v in re.findall(r"(\d+) \"", table)}
        self.assertEqual(sorted(set(codes) - have), [], "engine errors missing from the DBC's ST_LastErr")
        proto = read(os.path.join(ROOT, "config", "PROTOCOL.md"))
        m = re.search(r"7 last error \((.*?)\)\. Counters", proto)
        self.assertIsNotNone(m)
        listed = {int(v) for v in re.findall(r"(?<![\w.])(\d+) [a-z]", m.group(1).split(";")[0])}
        self.assertEqual(sorted(set(codes) - listed), [], "engine errors missing from STATUS byte 7")


class Paths(unittest.TestCase):
    def test_cited_paths_exist(self):
        docs = DOCS + glob.glob(os.path.join(ROOT, "lib", "*", "README.md")) + \
            glob.glob(os.path.join(ROOT, "daemon", "*", "README.md")) + \
            glob.glob(os.path.join(ROOT, "tests", "*", "README.md")) + \
            [os.path.join(ROOT, p) for p in ("daemon/README.md", "lib/engine/DESIGN.md")]
        bad = []
        for path in docs:
            for p in set(re.findall(r"(?<![\w/.-])((?:lib|daemon|config|tests|systemd)/[\w./-]*\w)", read(path))):
                if "*" in p or "<" in p or p.endswith((".", "/")):
                    continue
                full = os.path.join(ROOT, p)
                if not (os.path.exists(full) or glob.glob(full + "*")):
                    bad.append("%s: %s" % (os.path.relpath(path, ROOT), p))
        self.assertEqual(sorted(bad), [], "paths the documents cite that are not in the tree")


if __name__ == "__main__":
    unittest.main()
