"""The `summary: KEY VALUE` lines that `trajreplay --summary` writes to stderr
(daemon/replay/replay.c), as a dict of floats (the method's name as text)."""


def parse(stderr):
    out = {}
    for line in stderr.splitlines():
        if line.startswith("summary: "):
            k, v = line[len("summary: "):].split(" ", 1)
            out[k] = float(v) if k != "method" else v.strip()
    return out
