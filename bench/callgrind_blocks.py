#!/usr/bin/env python3
"""The hottest straight-line blocks of a function, from a callgrind profile taken with
`--dump-instr=yes`: per block its first address, length in instructions, how often it ran
and the instructions it cost, and with --show the disassembly of the hottest blocks with
each instruction's count. Deterministic (callgrind counts instructions, not time), so it
resolves steps of a few percent that timings on a shared 2-core machine cannot, and it
shows where a function's instructions go when line tables do not (inlined SIMD code is
attributed to the intrinsics' files, spills to no line at all).

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out \\
        target/release/spt rays trace /tmp/cbrays --no-write --passes 1
    python3 bench/callgrind_blocks.py cg.out traverse_avx2 target/release/spt --top 12 --show 3

A "block" here is a run of consecutive instructions with the same execution count, which
is a basic block or a few that always run together. Needs objdump (binutils) for --show.
"""
import argparse
import collections
import re
import subprocess
import sys


def parse_counts(path, pattern):
    """Ir per instruction address, for functions whose name matches `pattern`."""
    names = {}
    counts = collections.Counter()
    current = ""
    skip_next = False
    last = [0, 0]  # address, line: callgrind compresses positions relative to the last

    def position(token, i):
        if token == "*":
            return last[i]
        if token[0] in "+-":
            return last[i] + int(token)
        return int(token, 16) if token.startswith("0x") else int(token)

    name_re = re.compile(r"c?fn=\((\d+)\)(?: (.*))?")
    with open(path) as f:
        header = True
        for line in f:
            if header:
                if line.startswith("positions:") and "instr" not in line:
                    sys.exit(f"{path}: no instruction positions (record with --dump-instr=yes)")
                if line.startswith("fn=") or line.startswith("fl="):
                    header = False
            if line.startswith(("fn=", "cfn=")):
                m = name_re.match(line.strip())
                if m:
                    if m.group(2):
                        names[m.group(1)] = m.group(2)
                    if line.startswith("fn="):
                        current = names.get(m.group(1), "")
                continue
            if line.startswith("calls="):
                skip_next = True  # the next cost line is the call's inclusive cost
                continue
            if not line or not (line[0].isdigit() or line[0] in "+-*"):
                continue
            tokens = line.split()
            last[0] = position(tokens[0], 0)
            if len(tokens) > 1:
                last[1] = position(tokens[1], 1)
            if skip_next:
                skip_next = False
                continue
            if len(tokens) > 2 and pattern.search(current):
                counts[last[0]] += int(tokens[2])
    return counts


def blocks(counts, binary):
    """Runs of consecutive instructions (in the binary's order) with equal counts."""
    addresses = sorted(counts)
    order = disassemble(binary, addresses[0], addresses[-1]) if binary else None
    seq = [a for a, _ in order] if order else addresses
    out, start, run, prev = [], None, 0, None
    for a in seq:
        c = counts.get(a, 0)
        if c != prev:
            if run and prev:
                out.append((start, run, prev))
            start, run, prev = a, 0, c
        run += 1
    if run and prev:
        out.append((start, run, prev))
    return out, order


def disassemble(binary, lo, hi):
    try:
        text = subprocess.run(
            ["objdump", "-d", "--no-show-raw-insn", "-C", binary, f"--start-address={lo:#x}", f"--stop-address={hi + 16:#x}"],
            capture_output=True, text=True, check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        sys.exit(f"objdump on {binary} failed: {e}")
    rows = []
    for line in text.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
        if m:
            rows.append((int(m.group(1), 16), m.group(2)))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("profile", help="callgrind output recorded with --dump-instr=yes")
    ap.add_argument("function", help="regular expression on the function name")
    ap.add_argument("binary", nargs="?", help="the profiled binary (for block boundaries and --show)")
    ap.add_argument("--top", type=int, default=15, help="blocks to list")
    ap.add_argument("--show", type=int, default=0, help="disassemble the N hottest blocks")
    a = ap.parse_args()
    counts = parse_counts(a.profile, re.compile(a.function))
    if not counts:
        sys.exit(f"no instructions of a function matching {a.function!r} in {a.profile}")
    total = sum(counts.values())
    found, order = blocks(counts, a.binary)
    found.sort(key=lambda b: b[1] * b[2], reverse=True)
    print(f"{total:,} instructions in functions matching {a.function!r}")
    print(f"{'first address':>14} {'length':>7} {'runs':>12} {'instructions':>14} {'share':>7}")
    for start, n, c in found[: a.top]:
        print(f"{start:>14x} {n:>7} {c:>12,} {n * c:>14,} {n * c / total:>7.1%}")
    if a.show and not order:
        sys.exit("--show needs the binary")
    at = {addr: i for i, (addr, _) in enumerate(order or [])}
    for start, n, c in found[: a.show]:
        print(f"\n{start:x}: {n} instructions, run {c:,} times")
        i = at[start]
        for addr, text in order[i : i + n]:
            print(f"  {counts.get(addr, 0):>12,}  {addr:x}  {text[:100]}")


if __name__ == "__main__":
    main()
