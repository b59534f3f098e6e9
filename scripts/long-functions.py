#!/usr/bin/env python3
"""Lists functions longer than a limit (default 80 lines) in isokit's libraries and apps.

  scripts/long-functions.py [--limit N] [PATH ...]   (default: the libraries and apps)

A heuristic, not a parser: a function starts at a line of indentation 0 or 2 that ends with `{`
and is not a namespace, class, struct, enum, union or initializer; it ends at its matching brace
(braces in strings, characters and comments are skipped). Lambdas count towards their function.
"""
import argparse
import os
import re
import sys

SKIP = re.compile(r"^\s*(namespace|class|struct|enum|union|extern|template\s*<[^>]*>\s*(class|struct))\b")
DEFAULT = ["libcore", "liboperators", "libimplicit", "libtrack", "apps"]


def strip(line, state):
    """The line without strings, chars and comments; `state` carries block comments."""
    out, i = [], 0
    while i < len(line):
        if state["block"]:
            j = line.find("*/", i)
            if j < 0:
                return "".join(out)
            state["block"], i = False, j + 2
            continue
        c = line[i]
        if line.startswith("//", i):
            break
        if line.startswith("/*", i):
            state["block"], i = True, i + 2
            continue
        if c in "\"'":
            j = i + 1
            while j < len(line) and line[j] != c:
                j += 2 if line[j] == "\\" else 1
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().split("\n")
    state, code = {"block": False}, []
    for line in lines:
        code.append(strip(line, state))
    k, start = 0, 0  # start: first line of the current statement
    while k < len(code):
        line = code[k]
        text = line.strip()
        head = code[start]
        indent = len(head) - len(head.lstrip(" "))
        decl = " ".join(c.strip() for c in code[start:k + 1])
        if indent in (0, 2) and text.endswith("{") and not SKIP.match(decl) and decl != "{" \
                and "(" in decl and not decl.startswith("#") and "=" not in decl.split("(")[0]:
            depth, j = 0, k
            while j < len(code):
                depth += code[j].count("{") - code[j].count("}")
                if depth <= 0:
                    break
                j += 1
            yield decl.split("(")[0].split()[-1], start + 1, j - start + 1
            k = start = j + 1
            continue
        if not text or text.startswith("#") or text.endswith((";", "{", "}")) or text.endswith(":"):
            start = k + 1
        k += 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--limit", type=int, default=80)
    ap.add_argument("paths", nargs="*", default=DEFAULT)
    a = ap.parse_args()
    found = 0
    for root in a.paths:
        walk = [(root, [], [os.path.basename(root)])] if os.path.isfile(root) else os.walk(root)
        for d, _, files in walk:
            for fn in sorted(files):
                p = fn if os.path.isfile(root) else os.path.join(d, fn)
                if os.path.isfile(root):
                    p = root
                if not p.endswith((".cpp", ".h", ".cu", ".cuh")):
                    continue
                for name, line, n in functions(p):
                    if n > a.limit:
                        found += 1
                        print(f"{p}:{line}: {name} {n} lines")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
