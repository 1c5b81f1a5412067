#!/usr/bin/env python3
"""Sizes a reader can hold (CONTRIBUTING.md): no function over 150 lines in sdk/, adapters/ and tools/,
no file over 700 lines in sdk/. Prints each offender with its place and exits 1 when there is one.

A function is found the way the project's clang-format lays it out: a line that ends a signature with `{` (a
closing parenthesis, then qualifiers) opens a body that runs to its matching brace; lambdas count as the
functions they are. Comments, string and character literals are blanked before braces are counted."""
import os
import re
import sys

MAX_FUNCTION_LINES = 150
MAX_SDK_FILE_LINES = 700
ROOTS = ("sdk", "adapters", "tools")
SOURCE = (".cpp", ".h", ".hpp", ".cc")

SIGNATURE_END = re.compile(r"\)\s*(const|noexcept|override|final|mutable|->\s*[\w:<>,\s*&]+|\s)*\{\s*$")
CONTROL = re.compile(r"^\s*(\}\s*)?(if|for|while|switch|else|do|catch|return)\b")


def blank_literals(text):
    """The source with comments and literals replaced by spaces (line breaks kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(" " * (min(j + 1, n) - i))
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(lines):
    """(first line, line count) of every function body, 1-based."""
    found = []
    for start, line in enumerate(lines):
        if not SIGNATURE_END.search(line) or CONTROL.match(line):
            continue
        depth = 0
        for end in range(start, len(lines)):
            depth += lines[end].count("{") - lines[end].count("}")
            if depth <= 0:
                found.append((start + 1, end - start + 1))
                break
    return found


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    problems = []
    for top in ROOTS:
        for folder, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith(SOURCE):
                    continue
                path = os.path.join(folder, name)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8") as f:
                    text = f.read()
                lines = blank_literals(text).split("\n")
                count = text.count("\n")
                if top == "sdk" and count > MAX_SDK_FILE_LINES:
                    problems.append(f"{rel}: {count} lines (at most {MAX_SDK_FILE_LINES} in sdk/): split it by job")
                for first, length in functions(lines):
                    if length > MAX_FUNCTION_LINES:
                        problems.append(f"{rel}:{first}: a function of {length} lines (at most "
                                        f"{MAX_FUNCTION_LINES}): make it named steps")
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} size limit(s) exceeded (scripts/check_sizes.py)")
        return 1
    print("sizes: every function within %d lines, every sdk/ file within %d" % (MAX_FUNCTION_LINES,
                                                                              MAX_SDK_FILE_LINES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
