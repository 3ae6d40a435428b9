#!/usr/bin/env python3
"""Counts of how the source is laid out, for the closing notes of refactoring work (issue 50).

Prints, for the tree it is run in (default: the repository holding this file):
  - functions longer than a limit (default 80 lines), longest first, with their files;
  - lines of C++ and of GLSL, and the largest files;
  - how many files name a given word (a knob, a command), with --touches WORD ...

Functions are found by a brace scanner over comment- and string-free text: a '{' at namespace
or class scope whose head holds a parameter list and is not a control statement, a type or an
initialiser opens a function body; lambdas count inside the function that holds them. It is a
heuristic, good for counting, not a C++ parser.
"""
import argparse
import os
import re
import sys

SOURCE_DIRS = ["world", "renderer", "protocol", "config", "server", "cli", "image", "dataset",
               "bench", "tests"]
CXX = (".cpp", ".h", ".inc")
GLSL = (".glsl", ".vert", ".frag")


def strip(text):
    """Comments and string/char literals blanked out, newlines kept (raw strings too)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not text[i - 1].isalnum()):
            k = text.find("(", i)
            delim = ")" + text[i + 2:k] + '"'
            j = text.find(delim, k)
            j = n if j < 0 else j + len(delim)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


CONTROL = re.compile(r"^\s*(if|for|while|switch|catch|else|do|return|case)\b")
TYPE_HEAD = re.compile(r"\b(namespace|class|struct|union|enum)\b[^()]*$")


def functions(path):
    text = strip(open(path, encoding="utf-8", errors="replace").read())
    found = []
    stack = []  # 'scope' (namespace/class/extern) or 'function' or 'other'
    head_start = 0
    for i, c in enumerate(text):
        if c == "{":
            head = text[head_start:i]
            inside_function = "function" in stack
            kind = "other"
            if not inside_function:
                h = " ".join(head.split())
                if TYPE_HEAD.search(h) or h.startswith("extern") or not h:
                    kind = "scope"
                elif "(" in h and not CONTROL.match(h) and not h.rstrip().endswith("=") \
                        and not re.search(r"=\s*\{?$", h):
                    kind = "function"
                    name = re.findall(r"([~\w:]+)\s*\(", h)
                    found.append([name[0] if name else "?",
                                  text.count("\n", 0, head_start + len(head) - len(head.lstrip())) + 1,
                                  None])
            stack.append(kind)
            head_start = i + 1
        elif c == "}":
            if stack:
                kind = stack.pop()
                if kind == "function" and "function" not in stack:
                    found[-1][2] = text.count("\n", 0, i) + 1
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
        elif c == "#" and (i == 0 or text[i - 1] == "\n"):
            head_start = text.find("\n", i) + 1 or len(text)
    return [(name, end - start + 1, start) for name, start, end in found if end]


def tree_files(root, exts):
    for d in SOURCE_DIRS:
        for base, dirs, files in os.walk(os.path.join(root, d)):
            dirs[:] = [x for x in dirs if x not in ("build", "__pycache__")]
            for f in sorted(files):
                if f.endswith(exts):
                    yield os.path.join(base, f)


def main():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=here)
    ap.add_argument("--limit", type=int, default=80, help="longest function allowed (lines)")
    ap.add_argument("--touches", nargs="*", default=[],
                    help="words (a knob, a command) whose files are counted")
    args = ap.parse_args()
    root = args.root
    long_ones = []
    cxx_lines = 0
    sizes = []
    for path in tree_files(root, CXX):
        rel = os.path.relpath(path, root)
        n = sum(1 for _ in open(path, encoding="utf-8", errors="replace"))
        cxx_lines += n
        sizes.append((n, rel))
        if rel.startswith("tests/"):
            continue  # test bodies are tables of cases; the limit is for the product
        for name, length, line in functions(path):
            if length > args.limit:
                long_ones.append((length, f"{rel}:{line}", name))
    glsl_lines = sum(sum(1 for _ in open(p)) for p in tree_files(root, GLSL))
    long_ones.sort(reverse=True)
    print(f"functions over {args.limit} lines (tests excluded): {len(long_ones)}")
    for length, where, name in long_ones:
        print(f"  {length:5d}  {name}  {where}")
    print(f"lines of C++: {cxx_lines}; of GLSL files: {glsl_lines}")
    sizes.sort(reverse=True)
    print("largest files:", ", ".join(f"{rel} {n}" for n, rel in sizes[:6]))
    for word in args.touches:
        hits = []
        for path in list(tree_files(root, CXX + GLSL + (".py", ".toml"))) + \
                [os.path.join(root, "README.md")] + \
                [os.path.join(root, "docs", f) for f in sorted(os.listdir(os.path.join(root, "docs")))
                 if f.endswith(".md")]:
            if os.path.isfile(path) and word in open(path, encoding="utf-8", errors="replace").read():
                hits.append(os.path.relpath(path, root))
        print(f"files naming {word}: {len(hits)}: {' '.join(hits)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
