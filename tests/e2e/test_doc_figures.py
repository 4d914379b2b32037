"""test_doc_figures.py - every measured figure in the docs comes with the command that reproduces it.

Docs checked: README.md, config/*.md, daemon/*.md, lib/*/*.md, tests/*/*.md.
A doc is cut into blocks: paragraphs (separated by blank lines), tables (runs
of lines starting with '|') and fenced code blocks; a heading starts a new
section.

A *command* is a fenced code block, or an inline code span that starts with
make, build/, tests/, python3, sh, bash, BUILD=, FUZZ_, trajd, trajreplay,
trajsurf, tshark, mbpoll or candump.

Rules (a figure is flagged, with file:line, if it breaks one):
1. A paragraph that says "measured" (any case: Measured, re-measured) and
   holds a digit must contain a command, or the block before it in the same
   section must.
2. A table whose header row names a time or rate unit (ns, us, µs, ms, /s)
   and that has a data row with a digit must have a command in one of the
   two blocks before it in the same section.
3. No doc speaks of the machine or the session a figure was taken on
   ("load average", "this machine", "virtual machine", "shared 2-core",
   "other builds", "on a loaded machine", "quiet machine"): a figure is a
   property of the product, measured by its command; comparisons are ratios
   against a reference run in the same benchmark.
Deterministic counts (setpoints, waypoints of a replay) are checked against
their runs by the tests that produce them, not here.
"""
import glob
import os
import re
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
DOCS = ["README.md", "config/*.md", "daemon/*.md", "lib/*/*.md", "tests/*/*.md"]
COMMAND = re.compile(r"`(make|build/|tests/|python3|sh |bash |BUILD=|FUZZ_|trajd|trajreplay|"
                     r"trajsurf|tshark|mbpoll|candump)[^`]*`")
MACHINE_TALK = re.compile(r"load average|this machine|virtual machine|shared 2-core|2 cores shared|\d-CPU machine|"
                          r"other builds|loaded machine|quiet machine|nothing else (running|on)",
                          re.I)
UNIT_HEADER = re.compile(r"(\bns\b|\bus\b|µs|\bms\b|/s\b)")


def blocks(path):
    """[(section, kind, first line number, text)] of a Markdown file."""
    out, cur, kind, start, section, fence = [], [], None, 0, 0, False
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")

    def flush():
        nonlocal cur, kind
        if cur:
            out.append((section, kind, start, "\n".join(cur)))
        cur, kind = [], None

    for i, line in enumerate(lines, 1):
        if fence:
            cur.append(line)
            if line.lstrip().startswith("```"):
                fence = False
                flush()
            continue
        if line.lstrip().startswith("```"):
            flush()
            fence, kind, start, cur = True, "code", i, [line]
            continue
        if line.startswith("#"):
            flush()
            section += 1
            continue
        k = "table" if line.startswith("|") else ("code" if line.startswith("    ") and
                                                   kind in (None, "code") and not cur else "para")
        if not line.strip():
            flush()
            continue
        if kind is not None and k != kind and not (kind == "code" and line.startswith("    ")):
            flush()
        if kind is None:
            kind, start = k, i
        cur.append(line)
    flush()
    return out


def has_command(block):
    return block[1] == "code" or bool(COMMAND.search(block[3]))


def violations(path):
    bad = []
    bs = blocks(path)
    for j, b in enumerate(bs):
        section, kind, line, text = b
        before = [p for p in bs[max(0, j - 2):j] if p[0] == section]
        if kind == "para" and re.search(r"measured", text, re.I) and re.search(r"\d", text):
            if not has_command(b) and not (before and has_command(before[-1])):
                bad.append("%s:%d: 'measured' figure with no command nearby" % (path, line))
        if kind == "table":
            rows = text.split("\n")
            if (UNIT_HEADER.search(rows[0]) and any(re.search(r"\d", r) for r in rows[2:])
                    and not any(has_command(p) for p in before)):
                bad.append("%s:%d: table of measured figures with no command above it"
                           % (path, line))
    for section, kind, line, text in bs:
        for k, row in enumerate(text.split("\n")):
            if MACHINE_TALK.search(row):
                bad.append("%s:%d: speaks of the machine or the session: %s"
                           % (path, line + k, MACHINE_TALK.search(row).group(0)))
    return bad


class DocFigures(unittest.TestCase):
    def test_rule_flags_and_passes(self):
        # the rule itself, on a doc with each case
        import tempfile
        with tempfile.NamedTemporaryFile("w", suffix=".md", delete=False) as f:
            f.write("# A\n\nMeasured: 5 us per call.\n\n# B\n\nMeasured by `make bench`: 5 us.\n\n"
                    "# C\n\nRun:\n\n    build/bin/x\n\nMeasured: 7 ms.\n\n# D\n\n"
                    "| phase | p99 us |\n|---|---|\n| idle | 12 |\n\n# E\n\n`make bench`:\n\n"
                    "| phase | p99 us |\n|---|---|\n| idle | 12 |\n\n# F\n\nRun with `make bench` at load average 3.\n")
        try:
            got = [v.split(":")[1] for v in violations(f.name)]
            self.assertEqual(got, ["3", "19", "33"])
        finally:
            os.unlink(f.name)

    def test_docs(self):
        bad = []
        for pat in DOCS:
            for path in sorted(glob.glob(os.path.join(ROOT, pat))):
                bad += [os.path.relpath(v, ROOT) if v.startswith("/") else v
                        for v in violations(path)]
        self.assertEqual(bad, [], "\n" + "\n".join(bad))


if __name__ == "__main__":
    unittest.main()
