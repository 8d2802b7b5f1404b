#!/usr/bin/env python3
"""The README's marked code blocks, for tests/host/test_readme_install.sh.

A block the test runs is the fenced block right after a line
`<!-- readme-test: NAME [stream] -->`; the block after
`<!-- readme-test: NAME output -->` is what NAME prints.

  readme_blocks.py block README NAME          prints block NAME
  readme_blocks.py run README NAME [--sub OLD=NEW]...
      runs block NAME with sh (OLD replaced by NEW first) and checks that
      every line of its output block appears in what it printed. A line with
      a timestamp matches a printed line that differs only in numbers, hex
      data and times. A `stream` block runs until all lines were seen (or
      20 s), then is stopped; any other block must finish with status 0.
"""
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import time

MARK = re.compile(r"^<!-- readme-test: (\S+)((?: \S+)*) -->$")


def blocks(path):
    """{(name, 'output' or ''): (lines, flags)} of the marked blocks."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out = {}
    i = 0
    while i < len(lines):
        m = MARK.match(lines[i].strip())
        i += 1
        if not m:
            continue
        name, flags = m.group(1), m.group(2).split()
        while i < len(lines) and not lines[i].startswith("```"):
            i += 1
        i += 1
        body = []
        while i < len(lines) and not lines[i].startswith("```"):
            body.append(lines[i])
            i += 1
        key = (name, "output" if "output" in flags else "")
        if key in out:
            sys.exit(f"readme_blocks: {path}: block {name} {key[1]} marked twice")
        out[key] = (body, [f for f in flags if f != "output"])
    return out


def normalized(line):
    """The line with what changes from run to run (numbers, hex, times) blanked."""
    line = re.sub(r'"timestamp":"[^"]*"', '"timestamp":"T"', line)
    line = re.sub(r'"(raw|manufacturerData)":"[0-9a-f]*"', r'"\1":"H"', line)
    line = re.sub(r'":"-?[0-9]+"', '":"N"', line)
    line = re.sub(r'":-?[0-9]+(\.[0-9]+)?', '":N', line)
    return line


def matches(expected, printed):
    if expected == printed:
        return True
    return '"timestamp"' in expected and normalized(expected) == normalized(printed)


def run(path, name, subs):
    all_blocks = blocks(path)
    if (name, "") not in all_blocks:
        sys.exit(f"readme_blocks: {path} has no block {name}")
    body, flags = all_blocks[(name, "")]
    script = "\n".join(body)
    for s in subs:
        old, new = s.split("=", 1)
        script = script.replace(old, new)
    expected = [l for l in all_blocks.get((name, "output"), ([], []))[0] if l.strip() and l.strip() != "..."]
    stream = "stream" in flags
    print(f"--- running README block {name}{' (stream)' if stream else ''}:\n{script}\n---", flush=True)
    # stderr apart: progress meters (curl) must not break the printed lines.
    err = tempfile.TemporaryFile(mode="w+")
    proc = subprocess.Popen(["sh", "-ec", script], stdout=subprocess.PIPE, stderr=err,
                            start_new_session=True)
    printed = []
    missing = list(expected)
    deadline = time.monotonic() + 20
    fd = proc.stdout.fileno()
    buf = ""
    eof = False
    while time.monotonic() < deadline and not eof:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            chunk = os.read(fd, 65536)
            eof = not chunk
            buf += chunk.decode("utf-8", "replace")
            *done, buf = buf.split("\n")
            for l in done:
                printed.append(l)
                missing = [e for e in missing if not matches(e, l)]
        if stream and not missing and printed:
            break
    if eof:
        try:
            proc.wait(max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            pass
    if buf:
        printed.append(buf)
        missing = [e for e in missing if not any(matches(e, p) for p in printed)]
    still_running = proc.poll() is None
    if still_running:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(5)
    err.seek(0)
    shown = "\n".join(l[:300] for l in printed[:40]) + "\n--- stderr:\n" + err.read()[-2000:]
    if still_running and not stream:
        print(f"FAIL: README block {name} did not finish within 20 s; it printed:\n{shown}")
        return 1
    if not still_running and proc.returncode != 0 and not stream:
        print(f"FAIL: README block {name} exited with status {proc.returncode}; it printed:\n{shown}")
        return 1
    if missing:
        print(f"FAIL: README block {name} did not print, as the README says:\n" + "\n".join(missing) +
              f"\n--- it printed:\n{shown}")
        return 1
    print(f"PASS: README block {name}: {len(expected)} line(s) as the README shows")
    return 0


def main(argv):
    if len(argv) >= 4 and argv[1] == "block":
        all_blocks = blocks(argv[2])
        if (argv[3], "") not in all_blocks:
            sys.exit(f"readme_blocks: {argv[2]} has no block {argv[3]}")
        print("\n".join(all_blocks[(argv[3], "")][0]))
        return 0
    if len(argv) >= 4 and argv[1] == "run":
        subs = []
        rest = argv[4:]
        while rest:
            if rest[0] != "--sub" or len(rest) < 2:
                sys.exit(f"readme_blocks: unknown argument {rest[0]}")
            subs.append(rest[1])
            rest = rest[2:]
        return run(argv[2], argv[3], subs)
    sys.exit(__doc__)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
