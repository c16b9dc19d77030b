#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks that no function in Source/ is longer than 80 lines, signature to closing brace
(Documentation/architecture.md, "Layers"): C++ sources and headers, the GLSL shaders (read
as C) and the Python package. Functions are found by lizard (PyPI), which reads C++ without
compiling it. Exit status 1 with one line per function over the limit.

--self-test first checks that the measure sees a function of limit + 1 lines in each
language and passes one of exactly the limit.

usage: scripts/checks/check-function-length.py [--limit N] [--self-test] [SOURCE-DIR]
"""
import argparse
import os
import sys

import lizard

SUFFIXES = {".cxx": None, ".h": None, ".py": None, ".glsl": ".c"}


def functions(name, text):
    """(function name, first line, length) of each function of `text`, read by its suffix."""
    suffix = os.path.splitext(name)[1]
    as_name = name + SUFFIXES[suffix] if SUFFIXES[suffix] else name
    info = lizard.analyze_file.analyze_source_code(as_name, text)
    return [(f.name, f.start_line, f.length) for f in info.function_list]


def check(source, limit):
    problems, count = [], 0
    for folder, _, names in os.walk(source):
        for name in sorted(names):
            if os.path.splitext(name)[1] not in SUFFIXES:
                continue
            path = os.path.join(folder, name)
            with open(path, encoding="utf-8") as f:
                found = functions(path, f.read())
            count += len(found)
            problems += [f"{os.path.relpath(path, source)}:{line}: {function} is {length} lines"
                         f" (at most {limit})" for function, line, length in found
                         if length > limit]
    return problems, count


def body(suffix, lines):
    """A function of `lines` lines, signature to closing brace, in the language of suffix."""
    if suffix == ".py":
        return "def f():\n" + "    x = 1\n" * (lines - 1)
    head = "void f()\n" if suffix == ".glsl" else "void f(int a)\n"
    return head + "{\n" + "  a = a + 1;\n" * (lines - 3) + "}\n"


def self_test(limit):
    failures = []
    for suffix in SUFFIXES:
        for lines, reported in ((limit, False), (limit + 1, True)):
            found = functions("f" + suffix, body(suffix, lines))
            over = [length for _, _, length in found if length > limit]
            if bool(over) != reported:
                failures.append(f"self-test: a {lines}-line function in {suffix} was "
                                f"{'' if over else 'not '}reported")
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", nargs="?",
                        default=os.path.join(os.path.dirname(__file__), "..", "..", "Source"))
    parser.add_argument("--limit", type=int, default=80)
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        failures = self_test(args.limit)
        print("\n".join(failures) or f"self-test: functions of {args.limit + 1} lines reported "
              f"and of {args.limit} lines passed in {', '.join(SUFFIXES)}")
        if failures:
            return 1
    problems, count = check(args.source, args.limit)
    for problem in problems:
        print(problem)
    print(f"check-function-length: {count} functions, {len(problems)} over {args.limit} lines")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
