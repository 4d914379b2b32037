"""csource.py - a small reader of this project's C sources for the structure
tests (test_function_length.py, test_transport_seam.py): no compiler, no
dependency.  Good enough for code formatted by the tree's .clang-format; not a C parser.
"""
import re


def blank(src):
    """Comments, string and char literals, preprocessor lines -> spaces (newlines kept)."""
    out = []
    i, n = 0, len(src)
    line_start = True
    while i < n:
        c = src[i]
        if line_start and c == "#":
            # preprocessor line, with continuations
            while i < n and src[i] != "\n":
                if src[i] == "\\" and i + 1 < n and src[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        if c == "/" and src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
            continue
        if c == "/" and src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
            continue
        if c in "\"'":
            j = i + 1
            while j < n and src[j] != c:
                j += 2 if src[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + re.sub(r"[^\n]", " ", src[i + 1:j - 1]) + c)
            i = j
            continue
        if c == "\n":
            line_start = True
        elif not c.isspace():
            line_start = False
        out.append(c)
        i += 1
    return "".join(out)


def functions(path):
    """(name, first line, last line) of each function defined in path."""
    with open(path, encoding="utf-8", errors="replace") as f:
        src = blank(f.read())
    result = []
    depth = 0
    i = 0
    while i < len(src):
        c = src[i]
        if c == "{":
            if depth == 0:
                head = src[:i].rstrip()
                if head.endswith(")"):
                    # walk back over the parameter list to the name
                    k, par = len(head) - 1, 0
                    while k >= 0:
                        if head[k] == ")":
                            par += 1
                        elif head[k] == "(":
                            par -= 1
                            if par == 0:
                                break
                        k -= 1
                    m = re.search(r"([A-Za-z_]\w*)\s*$", head[:k])
                    if m:
                        first = src.count("\n", 0, m.start(1)) + 1
                        result.append([m.group(1), first, None, i])
            depth += 1
        elif c == "}":
            depth -= 1
            if depth == 0 and result and result[-1][2] is None:
                result[-1][2] = src.count("\n", 0, i) + 1
        i += 1
    return [(name, a, b) for name, a, b, _ in result if b is not None]
