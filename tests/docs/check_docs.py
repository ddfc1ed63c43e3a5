#!/usr/bin/env python3
"""Checks that the documentation is a usable map of the code.

Usage: check_docs.py REPO_ROOT

1. Every row of the tables in docs/equations.md names a file that exists and a function, class or
   struct that the file defines or declares: the identifier followed by `(`, or `class NAME` /
   `struct NAME`. A row whose file or function cell is not one backticked value is an error too,
   so that no row escapes the check.
2. Every `docs/<name>.md` that a source file, config, script or doc cites (*.cpp, *.hpp, *.json,
   *.py, *.md, *.sh anywhere in the repository except build trees and results) exists, and every
   relative Markdown link between docs resolves.
3. The reference docs (docs/*.md, not docs/notes/) and README.md say what is true now: no line
   matches `session [0-9]+` or `trial, not kept` (case-insensitive). Work logs go to docs/notes/.

Standard library only. Exits 0 when every check passes; otherwise prints one line per failure
and exits 1 (2 for bad usage).
"""
import os
import re
import sys

SCANNED_EXTENSIONS = (".cpp", ".hpp", ".json", ".py", ".md", ".sh")
# Directory names never scanned: version control, build trees (build, build-debug, build-asan,
# build-b, ...), results of experiment runs, caches.
SKIPPED_DIRS = {".git", "results", "__pycache__", "_deps", "node_modules", "Testing"}
EQUATIONS_HEADER = ["equation", "what it is", "file", "function"]
MIN_EQUATION_ROWS = 40  # the thesis's equations and algorithms; fewer means the parse broke
DOC_CITATION = re.compile(r"(?<![A-Za-z0-9_\-])docs/((?:[A-Za-z0-9_\-]+/)*[A-Za-z0-9_\-]+)\.md")
MD_LINK = re.compile(r"\]\(([^)\s#]+\.md)(?:#[^)\s]*)?\)")
WORK_LOG = re.compile(r"session [0-9]+|trial, not kept", re.IGNORECASE)
BACKTICKED = re.compile(r"^`([^`]+)`$")
IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(::[A-Za-z_~][A-Za-z0-9_]*)*$")


def skipped_dir(name):
    return name in SKIPPED_DIRS or name.startswith("build")


def read_text(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return f.read()


def split_row(line):
    """Cells of a Markdown table row, or None if the line is not one."""
    s = line.strip()
    if not s.startswith("|") or not s.endswith("|"):
        return None
    return [c.strip() for c in s[1:-1].split("|")]


def defines(text, ident):
    """Whether `text` has `ident(` or `class ident` / `struct ident`."""
    name = re.escape(ident)
    call = re.compile(r"(?<![A-Za-z0-9_:])" + name + r"\s*\(")
    if call.search(text):
        return True
    if "::" not in ident:
        decl = re.compile(r"\b(?:class|struct)\s+" + name + r"\b")
        if decl.search(text):
            return True
    return False


def check_equations(root, failures):
    path = os.path.join(root, "docs", "equations.md")
    rel = "docs/equations.md"
    if not os.path.isfile(path):
        failures.append(f"{rel}: missing")
        return
    rows = 0
    in_table = False
    for n, line in enumerate(read_text(path).splitlines(), 1):
        cells = split_row(line)
        if cells is None:
            in_table = False
            continue
        if [c.lower() for c in cells] == EQUATIONS_HEADER:
            in_table = True
            continue
        if not in_table or all(re.fullmatch(r":?-+:?", c) for c in cells):
            continue
        where = f"{rel}:{n}"
        if len(cells) != 4:
            failures.append(f"{where}: expected 4 cells (equation | what it is | file | function), "
                            f"got {len(cells)}")
            continue
        rows += 1
        fm, im = BACKTICKED.match(cells[2]), BACKTICKED.match(cells[3])
        if not fm:
            failures.append(f"{where}: file cell {cells[2]!r} is not one backticked path")
            continue
        if not im or not IDENTIFIER.match(im.group(1)):
            failures.append(f"{where}: function cell {cells[3]!r} is not one backticked identifier")
            continue
        file, ident = fm.group(1), im.group(1)
        full = os.path.join(root, file)
        if not os.path.isfile(full):
            failures.append(f"{where}: {cells[0]}: file {file} does not exist")
            continue
        if not defines(read_text(full), ident):
            failures.append(f"{where}: {cells[0]}: {file} has no `{ident}(` and no class or "
                            f"struct {ident}")
    if rows < MIN_EQUATION_ROWS:
        failures.append(f"{rel}: found {rows} table rows under the header "
                        f"'| {' | '.join(EQUATIONS_HEADER)} |', expected at least {MIN_EQUATION_ROWS}")


def scanned_files(root):
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not skipped_dir(d))
        for f in sorted(filenames):
            if f.endswith(SCANNED_EXTENSIONS):
                yield os.path.join(dirpath, f)


def check_citations(root, failures):
    for full in scanned_files(root):
        rel = os.path.relpath(full, root)
        for n, line in enumerate(read_text(full).splitlines(), 1):
            for m in DOC_CITATION.finditer(line):
                target = os.path.join(root, "docs", m.group(1) + ".md")
                if not os.path.isfile(target):
                    failures.append(f"{rel}:{n}: cites docs/{m.group(1)}.md, which does not exist")
            if rel.startswith("docs" + os.sep) and rel.endswith(".md"):
                for m in MD_LINK.finditer(line):
                    link = m.group(1)
                    if "://" in link or link.startswith("/"):
                        continue
                    target = os.path.normpath(os.path.join(os.path.dirname(full), link))
                    if not os.path.isfile(target):
                        failures.append(f"{rel}:{n}: links to {link}, which does not exist")


def check_work_log(root, failures):
    docs = os.path.join(root, "docs")
    paths = [os.path.join(root, "README.md")]
    if os.path.isdir(docs):
        paths += [os.path.join(docs, f) for f in sorted(os.listdir(docs)) if f.endswith(".md")]
    for full in paths:
        if not os.path.isfile(full):
            continue
        rel = os.path.relpath(full, root)
        for n, line in enumerate(read_text(full).splitlines(), 1):
            m = WORK_LOG.search(line)
            if m:
                failures.append(f"{rel}:{n}: work-log wording '{m.group(0)}' in a reference doc "
                                f"(move it to docs/notes/ or say what is true now)")


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    root = os.path.abspath(argv[1])
    if not os.path.isdir(os.path.join(root, "docs")):
        print(f"check_docs: {root} has no docs/ folder; expected the repository root", file=sys.stderr)
        return 2
    failures = []
    check_equations(root, failures)
    check_citations(root, failures)
    check_work_log(root, failures)
    for f in failures:
        print(f"FAIL {f}")
    if failures:
        print(f"check_docs: {len(failures)} failure(s)")
        return 1
    print("check_docs: docs/equations.md, doc citations and reference docs OK")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
