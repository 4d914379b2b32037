"""test_scale_config.py - how many objects a configuration may hold, and
what is refused when they do not fit (trajd --check-config, nothing runs):

  - 1024 objects replaying to stdout: accepted (CFG_OBJECTS_MAX);
  - 1025: refused at the 1025th section, with the limit;
  - 65 objects with the Modbus server on: refused, the register map holds
    ids 0..63 (an object with id 64 is named, with its line);
  - 64 with Modbus: accepted;
  - ids beyond the CAN defaults on a CAN output: refused with the reason.
"""
import os
import subprocess
import sys
import tempfile

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRACK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data",
                     "n2k_furuno_figure8_src52.csv")
failures = 0


def check(cond, what):
    global failures
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures += 1


def config(n, extra="", output="stdout", obj_extra=""):
    s = "[daemon]\nrate_hz = 100\n" + extra
    for i in range(n):
        s += ("[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\noutput = %s\n%s"
              % (i, i, TRACK, output, obj_extra))
    return s


def check_config(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "t.conf")
        with open(path, "w") as f:
            f.write(text)
        r = subprocess.run([TRAJD, "--check-config", path], capture_output=True, text=True,
                           timeout=120)
        return r.returncode, r.stdout + r.stderr


def main():
    rc, out = check_config(config(1024))
    check(rc == 0, "1024 objects accepted (exit %d) %s" % (rc, out.strip()[-200:]))
    rc, out = check_config(config(1025))
    check(rc != 0 and "more than 1024 objects" in out,
          "1025 objects refused with the limit: %s" % out.strip()[-200:])
    modbus = "[modbus]\naddress = 127.0.0.1\nport = 0\n"
    rc, out = check_config(config(64, modbus))
    check(rc == 0, "64 objects with Modbus accepted (exit %d) %s" % (rc, out.strip()[-200:]))
    rc, out = check_config(config(65, modbus))
    check(rc != 0 and "o64" in out and "0..63" in out,
          "65 objects with Modbus refused, naming the object and the map's ids: %s"
          % out.strip()[-200:])
    can = "[can]\ninterface = vcan-none\n"
    rc, out = check_config(config(200, can, output="can"))
    check(rc != 0 and ("CAN" in out or "can" in out),
          "200 objects on CAN refused with the reason: %s" % out.strip()[-200:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
