#!/usr/bin/env python3
"""Fails when a function in libcore/ or tools/ is longer than 80 lines (issue 18: no function over
80 lines). A function is a definition at namespace scope as clang-format lays it out (.clang-format
in the repo): its signature starts at column 0 and its body ends with "}" at column 0; its length
is from the signature's first line to that "}". Lambdas and local classes count toward the
function that holds them.

usage: check_function_length.py [--root DIR] [--max N] [--self-test]
"""
import argparse
import os
import re
import sys
import tempfile

SKIP = re.compile(r"^(namespace|class|struct|enum|union|extern|template\s*<[^>]*>\s*(class|struct)|#|//|/\*|\}|using|typedef)")


def functions(path):
    """(name, first line, length) of each namespace-scope function definition in `path`."""
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        if not line or line[0].isspace() or SKIP.match(line) or "(" not in line:
            i += 1
            continue
        # The signature runs to the first line ending with "{" (or ";" for a declaration).
        j = i
        while j < len(lines) and not lines[j].rstrip().endswith("{") and \
                not lines[j].rstrip().endswith(";") and j - i < 12:
            j += 1
        if j >= len(lines) or not lines[j].rstrip().endswith("{") or "=" in line.split("(")[0]:
            i = j + 1
            continue
        if lines[j].rstrip().endswith("{") and lines[j].strip().endswith("}"):
            i = j + 1  # a one-line body
            continue
        k = j + 1
        while k < len(lines) and lines[k] != "}" and not lines[k].startswith("}"):
            k += 1
        name = re.sub(r"\s+", " ", line.split("(")[0]).split(" ")[-1]
        out.append((name, i + 1, k - i + 1))
        i = k + 1
    return out


def check(root, limit):
    bad = []
    for top in ("libcore", "tools"):
        for d, _, files in os.walk(os.path.join(root, top)):
            for f in sorted(files):
                if f.endswith((".cpp", ".h")):
                    p = os.path.join(d, f)
                    for name, line, n in functions(p):
                        if n > limit:
                            bad.append(f"{os.path.relpath(p, root)}:{line}: {name} is {n} lines "
                                       f"(at most {limit})")
    return bad


def self_test(limit):
    with tempfile.TemporaryDirectory() as t:
        os.makedirs(os.path.join(t, "libcore", "m"))
        os.makedirs(os.path.join(t, "tools"))
        body = "\n".join(f"  x += {i};" for i in range(limit - 2))
        src = ("namespace mvtm {\n\nint Short(int x) {\n" + body + "\n}\n\n"
               "int Long(int x,\n         int y) {\n" + body + "\n  auto f = [&] {\n    return 1;\n  };\n}\n"
               "\n}  // namespace mvtm\n")
        open(os.path.join(t, "libcore", "m", "a.cpp"), "w").write(src)
        bad = check(t, limit)
        ok = len(bad) == 1 and "Long is" in bad[0]
        print("\n".join(bad))
        print("self-test", "passed" if ok else "FAILED: expected exactly Long to be reported")
        return 0 if ok else 1


ap = argparse.ArgumentParser()
ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
ap.add_argument("--max", type=int, default=80)
ap.add_argument("--self-test", action="store_true")
a = ap.parse_args()
if a.self_test:
    sys.exit(self_test(a.max))
problems = check(a.root, a.max)
print("\n".join(problems))
print(f"{len(problems)} functions over {a.max} lines")
sys.exit(1 if problems else 0)
