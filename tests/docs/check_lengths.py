#!/usr/bin/env python3
"""Checks the size limits of the layout: no source file over 1,000 lines and
no function body over 150 lines in the given folders.

A function is found as a line that ends a signature with '{' at brace depth 0
(or depth 1 inside a namespace); its length runs to the matching brace. String
and character literals and comments are skipped when counting braces.

Usage: check_lengths.py ROOT FOLDER... [--max-file N] [--max-function N]
"""
import pathlib
import re
import sys


def strip_code(text):
    """Returns text with comments and literals blanked, newlines kept."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = ')' + (m.group(1) if m else '') + '"'
            j = text.find(end, i)
            j = n if j < 0 else j + len(end)
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            i = j + 1
            out.append("0")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    """Yields (name, first line, line count) of each function body in path."""
    code = strip_code(path.read_text(encoding="utf-8"))
    lines = code.split("\n")
    depth = 0
    namespace_depths = set()
    open_fn = None
    pending = ""
    for number, line in enumerate(lines, start=1):
        for k, c in enumerate(line):
            if c == "{":
                head = (pending + " " + line[:k]).strip()
                if re.search(r"\bnamespace\b[^;{}]*$", head) or re.search(
                        r'extern\s+"?C?"?\s*$', head):
                    namespace_depths.add(depth)
                elif (open_fn is None and depth in {d + 1 for d in namespace_depths} | {0}
                      and re.search(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*"
                                    r"(->\s*[\w:<>, ]+)?\s*(:.*)?$", head)
                      and not re.search(r"\b(class|struct|enum|union)\b", head)
                      and not head.rstrip().endswith("=")):
                    name = re.findall(r"([\w:~]+)\s*\(", head)
                    open_fn = (name[0] if name else "?", number, depth)
                depth += 1
                pending = ""
            elif c == "}":
                depth -= 1
                namespace_depths.discard(depth)
                if open_fn and depth == open_fn[2]:
                    yield open_fn[0], open_fn[1], number - open_fn[1] + 1
                    open_fn = None
                pending = ""
            elif c == ";":
                pending = ""
        if not line.strip().startswith("#"):
            pending += " " + line


def main(argv):
    max_file, max_function = 1000, 150
    args = []
    it = iter(argv[1:])
    for a in it:
        if a == "--max-file":
            max_file = int(next(it))
        elif a == "--max-function":
            max_function = int(next(it))
        else:
            args.append(a)
    if len(args) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(args[0])
    problems = []
    for folder in args[1:]:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in {".cpp", ".hpp", ".h", ".cc"}:
                continue
            rel = path.relative_to(root)
            count = len(path.read_text(encoding="utf-8").splitlines())
            if count > max_file:
                problems.append(f"{rel}: {count} lines (limit {max_file})")
            for name, first, length in functions(path):
                if length > max_function:
                    problems.append(
                        f"{rel}:{first}: function {name} is {length} lines (limit {max_function})")
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} size limit(s) exceeded", file=sys.stderr)
        return 1
    print(f"size limits hold in {', '.join(args[1:])}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
