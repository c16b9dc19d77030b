#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks that no function in Source/ is longer than 80 lines, signature to closing brace
(Documentation/architecture.md, "Layers"): C++ sources and headers, the GLSL shaders (read
as C) and the Python package. Exit status 1 with one line per function over the limit.

A function's lines run from the first line of its signature to its closing brace, both
included, with every comment and blank line between: in C++ the signature starts at the
first of the lines above the function's name that continue it (a template header, a return
type or an attribute on a line of its own). In Python a function runs from its `def` to
its last statement. Functions are found by lizard (PyPI), which reads C++ without compiling
it; lizard gives the line of the name and that of the closing brace.

--self-test first checks the measure: a function of limit + 1 lines is reported and one of
exactly the limit is not, in each language, with a body of code or mostly of comments, with
a signature over several lines, and after a file-scope expression that compares with `<`.

usage: scripts/checks/check-function-length.py [--limit N] [--self-test] [SOURCE-DIR]
"""
import argparse
import os
import re
import sys

import lizard
from lizard_languages.clike_states import CLikeStates

SUFFIXES = {".cxx": None, ".h": None, ".py": None, ".glsl": ".c"}


def _global_state_closes_brackets():
    """lizard 1.24 keeps the brackets of a parenthesised expression at file or class scope
    on its stack of open brackets when a `<` in it is a comparison or a shift (as in
    `static_assert(a < (b << 31))`); the stack stays unbalanced and every later function of
    the file is read wrongly or not at all. Outside any declaration no bracket is open: the
    global state starts with an empty stack."""
    state_global = CLikeStates._state_global

    def state_global_with_no_open_brackets(self, token):
        self.bracket_stack = []
        state_global(self, token)

    CLikeStates._state_global = state_global_with_no_open_brackets


_global_state_closes_brackets()

# A line above a C++ function's name that cannot continue its signature: blank, a comment or
# a preprocessor line, or the end of what comes before (a statement, a block, an access
# specifier such as `public:`).
_NOT_SIGNATURE = re.compile(r"^\s*($|//|/\*|\*|#)|(?<!:)[;{}:]\s*$|\*/\s*$")


def signature_start(lines, name_line):
    """The first line (1-based) of the C++ signature whose name lies on `name_line`."""
    first = name_line
    while first > 1:
        above = re.sub(r"\s//.*$", "", lines[first - 2])
        if _NOT_SIGNATURE.search(above):
            break
        first -= 1
    return first


def functions(name, text):
    """(function name, first line, length) of each function of `text`, read by its suffix."""
    suffix = os.path.splitext(name)[1]
    as_name = name + SUFFIXES[suffix] if SUFFIXES[suffix] else name
    info = lizard.analyze_file.analyze_source_code(as_name, text)
    lines = text.splitlines()
    found = []
    for f in info.function_list:
        first = f.start_line if suffix == ".py" else signature_start(lines, f.start_line)
        found.append((f.name, first, f.end_line - first + 1))
    return found


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


def body(suffix, lines, shape):
    """Source text holding a function f of `lines` lines, signature to closing brace (Python:
    to its last statement), in the language of suffix, of the given shape:
      code       one statement a line;
      comments   a body of comments and blank lines, then one statement;
      signature  a signature over several lines (C++: a template header and the return type
                 above the name, the parameters below it; Python: the parameters);
      compare    after a file-scope static_assert that compares and shifts, and an array
                 with an initialiser."""
    if suffix == ".py":
        head = "def f(a,\n      b):\n" if shape == "signature" else "def f():\n"
        filler = "    # a comment\n\n" if shape == "comments" else "    x = 1\n    x = 2\n"
        rest = lines - head.count("\n") - 1
        return "import os\n\n\n" + head + filler_lines(filler, rest) + "    x = 0\n"
    prologue = "// A file.\nint g;\n\n"
    if shape == "compare":
        prologue += "static_assert(2 * 3 * (4 + 5) < (long{ 1 } << 31), \"fits\");\nint t[4] = {};\n"
    prologue += "\n/// The function.\n"
    if shape == "signature":
        head = "template <typename T,\n  typename U>\nstatic inline int\nf(T a,\n  U b)\n{\n"
    else:
        head = ("void f()\n" if suffix == ".glsl" else "void f(int a)\n") + "{\n"
    filler = "  // a comment\n\n" if shape == "comments" else "  a = a + 1;\n  a = a * 2;\n"
    rest = lines - head.count("\n") - 2
    return prologue + head + filler_lines(filler, rest) + "  a = 0;\n}\n"


def filler_lines(filler, count):
    """`count` lines, taken in turn from the two lines of `filler`."""
    two = filler.splitlines(keepends=True)
    return "".join(two[i % 2] for i in range(count))


def self_test(limit):
    failures = []
    for suffix in SUFFIXES:
        shapes = ["code", "comments", "signature"] + ([] if suffix == ".py" else ["compare"])
        if suffix == ".glsl":
            shapes.remove("signature")  # GLSL has no templates
        for shape in shapes:
            for lines, reported in ((limit, False), (limit + 1, True)):
                found = [(length, line) for name, line, length
                         in functions("f" + suffix, body(suffix, lines, shape)) if name == "f"]
                if [length for length, _ in found] != [lines]:
                    failures.append(f"self-test: a {lines}-line function in {suffix} ({shape})"
                                    f" was measured as {found} (length, first line)")
                elif (lines > limit) != reported:
                    failures.append(f"self-test: a {lines}-line function in {suffix} ({shape})"
                                    f" was {'' if lines > limit else 'not '}reported")
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
              f"and of {args.limit} lines passed in {', '.join(SUFFIXES)}: bodies of code and "
              f"of comments, signatures over several lines, after a file-scope comparison")
        if failures:
            return 1
    problems, count = check(args.source, args.limit)
    for problem in problems:
        print(problem)
    print(f"check-function-length: {count} functions, {len(problems)} over {args.limit} lines")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
