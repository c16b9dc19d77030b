#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks that no source file includes a header of a room above its own, or of a room beside
it (Documentation/architecture.md, "The house").

The rooms are folders, and their layers are read from the build, never listed here:
- the core (Source/Core): `mtpt_core_layers` in Source/Core/CMakeLists.txt, lowest layer
  first; the rooms on one line share a layer. A file's room is the folder it lies in; a room
  includes its own headers and those of lower layers, its public headers as "mtpt/Name.h"
  and its internal ones as "detail/Name.h", wherever they lie;
- the VTK module (Source/VTK): `mtpt_module_layers` in Source/VTK/CMakeLists.txt, the same
  way; "." is the module's top folder (the mapper). The module includes the core's public
  headers (mtpt/), never its internals (detail/). A public header placed at the top for
  VTK's module system but belonging to a lower room is named in PLACED_AT_TOP.
Inside a room, the includes between its own files form no cycle, so each room reads in one
order. A file no room holds, an include that names no header of ours, and a fragment
("-inl.h") included from another room are errors too. Exit status 1 with one line per
problem. --self-test injects each kind of fault into a copy of the sources and checks that
it is reported, alone, and that the unchanged copy passes.

usage: scripts/checks/check-layers.py [--self-test] [SOURCE-DIR]   (default: Source)
"""
import os
import re
import shutil
import sys
import tempfile

INCLUDE = re.compile(r'\s*#\s*include\s+"([^"]+)"')
LAYERS = re.compile(r"set\(\s*(\w+_layers)\s+(.*?)\)", re.S)
# Public headers that VTK's module system installs from the module's top folder, and the
# room each belongs to.
PLACED_AT_TOP = {"vtkMTPTVTKCompatibility.h": "Basics"}
SOURCE_SUFFIXES = (".h", ".cxx")


def read_layers(cmake_file, variable):
    """{room: layer} from `set(variable "A" "B C" ...)` in cmake_file (comments dropped)."""
    with open(cmake_file, encoding="utf-8") as f:
        text = "\n".join(line.split("#")[0] for line in f)
    for match in LAYERS.finditer(text):
        if match.group(1) == variable:
            layers = re.findall(r'"([^"]*)"', match.group(2))
            return {room: layer for layer, rooms in enumerate(layers) for room in rooms.split()}
    raise SystemExit(f"check-layers: no set({variable} ...) in {cmake_file}")


class Part:
    """One part of the tree (the core or the module): its rooms and their files."""

    def __init__(self, name, folder, layers):
        self.name, self.folder, self.layers = name, folder, layers
        self.files = {}  # path relative to folder -> room
        self.problems = []
        for path in sorted(self.walk()):
            room = path.split("/")[0] if "/" in path else "."
            room = PLACED_AT_TOP.get(path, room)
            if room not in layers:
                self.problems.append(f"{name}/{path}: in no room of the layers list")
                continue
            self.files[path] = room

    def walk(self):
        for top, _, names in os.walk(self.folder):
            for n in names:
                if n.endswith(SOURCE_SUFFIXES):
                    yield os.path.relpath(os.path.join(top, n), self.folder).replace(os.sep, "/")

    def resolve(self, including, included):
        """The file of ours `included` names from `including`, or None."""
        beside = os.path.normpath(os.path.join(os.path.dirname(including), included))
        if beside in self.files:
            return beside
        found = [p for p in self.files
                 if p == included or p.endswith("/" + included) or
                 os.path.basename(p) == included and included.startswith("vtk")]
        return found[0] if len(found) == 1 else None


def check_part(part, is_ours, forbidden=()):
    """Adds to part.problems every include that runs up, sideways or into forbidden paths;
    returns the includes between files of one room."""
    edges = {}
    for path, room in part.files.items():
        for number, included in includes(os.path.join(part.folder, path)):
            where = f"{part.name}/{path}:{number}"
            if any(included.startswith(f) for f in forbidden):
                part.problems.append(f"{where}: includes the core's internal {included}")
                continue
            target = part.resolve(path, included)
            if target is None:
                if is_ours(included):
                    part.problems.append(f"{where}: {included} is no header of {part.name}")
                continue
            theirs = part.files[target]
            if target.endswith("-inl.h") and theirs != room:
                part.problems.append(f"{where}: includes the fragment {target} of the room "
                                     f"{theirs}")
            elif part.layers[theirs] > part.layers[room]:
                part.problems.append(f"{where}: the room {room} (layer {part.layers[room]}) "
                                     f"includes {included} of the room {theirs} (layer "
                                     f"{part.layers[theirs]}), above it")
            elif theirs != room and part.layers[theirs] == part.layers[room]:
                part.problems.append(f"{where}: the room {room} includes {included} of the "
                                     f"room {theirs} beside it")
            elif theirs == room and target != path:
                edges.setdefault(path, set()).add(target)
    for cycle in cycles(edges):
        part.problems.append(f"{part.name}/{cycle[0]}: an include cycle inside its room: "
                             + " -> ".join(cycle + [cycle[0]]))


def cycles(edges):
    """Cycles of `edges` (file -> files it includes): the first found from each root."""
    found, state = [], {}

    def visit(node, stack):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                found.append(stack[stack.index(nxt):])
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = 2

    reported = []
    for node in sorted(edges):
        if node not in state:
            before = len(found)
            visit(node, [])
            reported += found[before:before + 1]  # one cycle per search: the first found
    return reported


def includes(path):
    with open(path, encoding="utf-8") as source:
        for number, line in enumerate(source, 1):
            match = INCLUDE.match(line)
            if match:
                yield number, match.group(1)


def check(source):
    core_dir, vtk_dir = os.path.join(source, "Core"), os.path.join(source, "VTK")
    core = Part("Core", core_dir, read_layers(os.path.join(core_dir, "CMakeLists.txt"),
                                              "mtpt_core_layers"))
    module = Part("VTK", vtk_dir, read_layers(os.path.join(vtk_dir, "CMakeLists.txt"),
                                              "mtpt_module_layers"))
    check_part(core, lambda h: h.startswith(("mtpt/", "detail/")) or h.endswith("-inl.h"))
    # The module's own headers are found by their room's folder, or by name (vtkMTPT*.h).
    check_part(module, lambda h: h.split("/")[0] in module.layers and "/" in h,
               forbidden=("detail/",))
    return len(core.files) + len(module.files), core.problems + module.problems


def self_test(source):
    """Each injected fault must be reported by the check, and nothing else."""
    faults = [
        ("Core/Stages/mtpt/DepthKeys.h", '#include "mtpt/FramePipeline.h"', "above it"),
        ("Core/Vocabulary/mtpt/Records.h", '#include "detail/Parallel.h"', "above it"),
        ("Core/Compositor/Compositor.cxx", '#include "mtpt/ReferenceRenderer.h"', "beside it"),
        ("Core/Stages/mtpt/DepthKeys.h", '#include "mtpt/VisibilityOrder.h"', "include cycle"),
        ("Core/Stages/Culling.cxx", '#include "mtpt/NoSuchStage.h"', "no header of Core"),
        ("Core/Pipeline/FramePipeline.cxx", '#include "detail/FanPath-inl.h"', "the fragment"),
        ("VTK/Input/MeshSource.h", '#include "Drawing/CPUBackend.h"', "above it"),
        ("VTK/Reference/vtkMTPTReferenceRenderer.cxx", '#include "Drawing/RenderBackend.h"',
         "beside it"),
        ("VTK/Drawing/RenderBackend.h", '#include "Drawing/CPUBackend.h"', "include cycle"),
        ("VTK/Drawing/OpenGLBackend.cxx", '#include "detail/Parallel.h"', "internal"),
    ]
    ok = True
    with tempfile.TemporaryDirectory() as scratch:
        copy = os.path.join(scratch, "Source")
        shutil.copytree(os.path.join(source, "Core"), os.path.join(copy, "Core"))
        shutil.copytree(os.path.join(source, "VTK"), os.path.join(copy, "VTK"))
        _, clean = check(copy)
        if clean:
            print("self-test: the unchanged copy fails:\n  " + "\n  ".join(clean))
            ok = False
        for relative, line, expected in faults:
            path = os.path.join(copy, relative)
            with open(path, encoding="utf-8") as f:
                original = f.read()
            with open(path, "w", encoding="utf-8") as f:
                f.write(original + "\n" + line + "\n")
            _, found = check(copy)
            with open(path, "w", encoding="utf-8") as f:
                f.write(original)
            caught = [p for p in found if expected in p]
            alone = bool(caught) and len(found) == 1
            print(f"self-test: {line} in {relative}: "
                  f"{'reported' if alone else 'NOT REPORTED ALONE: ' + '; '.join(found)}")
            ok &= alone
    return ok


def main():
    args = [a for a in sys.argv[1:] if a != "--self-test"]
    here = os.path.dirname(os.path.abspath(__file__))
    source = args[0] if args else os.path.join(here, "..", "..", "Source")
    if "--self-test" in sys.argv[1:]:
        return 0 if self_test(source) else 1
    count, problems = check(source)
    for problem in problems:
        print(problem)
    print(f"check-layers: {count} files, {len(problems)} includes running up, sideways, in a "
          f"cycle or into the core's internals, or files of no room")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
