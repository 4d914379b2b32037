"""The `summary: KEY VALUE` lines that `trajreplay --summary` writes to stderr
(daemon/replay/replay.c), as a dict of floats."""


def parse(stderr):
    out = {}
    for line in stderr.splitlines():
        if line.startswith("summary: "):
            k, v = line[len("summary: "):].split(" ", 1)
            out[k] = float(v)
    return out
