#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks that no source file includes a header above it (Documentation/architecture.md,
"The stages of a frame" and "Layers").

The core (Source/Core), from the lowest layer:
  0  vocabulary: mtpt/MeshView.h, Records.h, SegmentShared.h, Shading.h, Stage.h, Threads.h,
     Timing.h, TransferFunctionTable.h, Lighting.h
  1  helpers: detail/*.h; fragments of a source file (FanRaster-inl.h, FragmentFloor-inl.h)
     lie beside it
  2  stages, in the order a frame runs them; a stage includes only earlier ones:
     mtpt/Transform.h, Culling.h, LevelOfDetail.h, DepthKeys.h, NearPlane.h,
     VisibilityOrder.h, Decompose.h
  3  assemblies: mtpt/Compositor.h, FramePipeline.h, ReferenceRenderer.h, ImageSampling.h,
     Gradients.h
The VTK module (Source/VTK), in rooms, each a folder; each includes the core's public headers
(mtpt/, never detail/) and the rooms it lists, and inside a room a file includes only those
before it:
  basics     Basics/: VTKCompatibility.h, OpenGLHeader.h; and the public
             vtkMTPTVTKCompatibility.h at the top
  input      Input/: VolumeInput.h, Tetrahedralizer.h, MeshAdapter.h, MeshSource.h,
             TransferFunctionTables.h, DependentColours.h            (basics)
  drawing    Drawing/: RenderBackend.h, BlendTarget.h, VolumetricPeel.h, ImagePath.h,
             CPUBackend.h and OpenGLBackend.h (the two backends side by side)
                                                                     (basics, input)
  reference  Reference/: vtkMTPTReferenceRenderer.h                  (basics, input)
  mapper     the top: vtkMultiThreadedProjectedTetrahedraMapper.h    (basics, input, drawing)
A source file belongs to the place of the header it implements, and lies in its room's
folder. Exit status 1 with one line
per include that runs upward, sideways or into the core's internals; a header the tables do
not know is an error too. --self-test injects such includes into a copy of the sources and
checks that each is reported, and that the copy without them passes.

usage: scripts/check-layers.py [--self-test] [SOURCE-DIR]   (default: Source beside this script)
"""
import os
import re
import shutil
import sys
import tempfile

STAGES = ["Transform", "Culling", "LevelOfDetail", "DepthKeys", "NearPlane", "VisibilityOrder",
          "Decompose"]
CORE = {
    **{f"mtpt/{name}.h": (0, 0) for name in
       ["MeshView", "Records", "SegmentShared", "Shading", "Stage", "Threads", "Timing",
        "TransferFunctionTable", "Lighting"]},
    **{f"mtpt/{name}.h": (2, rank) for rank, name in enumerate(STAGES)},
    **{f"mtpt/{name}.h": (3, 0) for name in
       ["Compositor", "FramePipeline", "ReferenceRenderer", "ImageSampling", "Gradients"]},
}
# Core sources whose header is not named after them, and fragments of a source (beside it).
CORE_SOURCES = {"TileRaster.cxx": "detail/TileRaster.h",
                "FanRaster-inl.h": "detail/TileRaster.h",
                "FragmentFloor-inl.h": "detail/TileRaster.h",
                "DecomposeBatch.cxx": "detail/DecomposeBatch.h",
                "KeyBatch.cxx": "detail/KeyBatch.h"}

# room -> (folder, its headers in order, the rooms it may include). Headers are named by
# their path in Source/VTK, which is how the module includes them.
ROOMS = {
    "basics": ("Basics", ["vtkMTPTVTKCompatibility.h", "Basics/VTKCompatibility.h",
                          "Basics/OpenGLHeader.h"], []),
    "input": ("Input", ["Input/VolumeInput.h", "Input/Tetrahedralizer.h", "Input/MeshAdapter.h",
                        "Input/MeshSource.h", "Input/TransferFunctionTables.h",
                        "Input/DependentColours.h"], ["basics"]),
    "drawing": ("Drawing", ["Drawing/RenderBackend.h", "Drawing/BlendTarget.h",
                            "Drawing/VolumetricPeel.h", "Drawing/ImagePath.h",
                            ("Drawing/CPUBackend.h", "Drawing/OpenGLBackend.h")],
                ["basics", "input"]),
    "reference": ("Reference", ["Reference/vtkMTPTReferenceRenderer.h"], ["basics", "input"]),
    "mapper": ("", ["vtkMultiThreadedProjectedTetrahedraMapper.h"], ["basics", "input", "drawing"]),
}
# Public headers live at the top, whatever their room; other files in their room's folder.
PUBLIC = {"vtkMTPTVTKCompatibility.h"}
VTK = {}  # header -> (room, rank in the room)
for room, (_, members, _) in ROOMS.items():
    for rank, member in enumerate(members):
        for header in (member if isinstance(member, tuple) else (member,)):
            VTK[header] = (room, rank)
# A public header in a folder of its own (vtkMTPT*.h) is also included by its name alone.
BY_NAME = {os.path.basename(h): h for h in VTK if os.path.basename(h).startswith("vtk")}

INCLUDE = re.compile(r'\s*#\s*include\s+"([^"]+)"')


def core_place(header):
    if header.startswith("detail/"):
        return (1, 0)
    return CORE[header]


def check_core(core, problems):
    files = [os.path.join(folder, name) if folder else name
             for folder in ("mtpt", "detail", "")
             for name in sorted(os.listdir(os.path.join(core, folder)))
             if name.endswith((".h", ".cxx"))]
    for name in files:
        if name in CORE_SOURCES:
            own = CORE_SOURCES[name]
        else:
            own = "mtpt/" + name[:-4] + ".h" if name.endswith(".cxx") else name
        try:
            mine = core_place(own)
        except KeyError:
            problems.append(f"Core/{name}: its layer is unknown (add {own} to CORE)")
            continue
        for number, included in includes(os.path.join(core, name)):
            if included == own or not included.startswith(("mtpt/", "detail/")):
                continue
            try:
                theirs = core_place(included)
            except KeyError:
                problems.append(f"Core/{name}:{number}: {included} has no layer")
                continue
            if theirs[0] > mine[0]:
                problems.append(f"Core/{name}:{number}: includes {included} (layer {theirs[0]}) "
                                f"from layer {mine[0]}")
            elif theirs[0] == mine[0] == 2 and theirs[1] > mine[1]:
                problems.append(f"Core/{name}:{number}: the stage {STAGES[mine[1]]} includes "
                                f"{included}, a later stage")
    return len(files)


def check_vtk(vtk, problems):
    files = sorted(os.path.relpath(os.path.join(folder, name), vtk)
                   for folder, _, names in os.walk(vtk) for name in names
                   if name.endswith((".h", ".cxx")))
    for name in files:
        own = name[:-4] + ".h" if name.endswith(".cxx") else name
        if own not in VTK:
            problems.append(f"VTK/{name}: its room is unknown (add {own} to ROOMS)")
            continue
        room, rank = VTK[own]
        folder = "" if own in PUBLIC else ROOMS[room][0]
        if os.path.dirname(name) != folder:
            problems.append(f"VTK/{name}: of the room {room}, outside its folder "
                            f"{folder or 'Source/VTK'}")
        for number, included in includes(os.path.join(vtk, name)):
            where = f"VTK/{name}:{number}"
            included = BY_NAME.get(included, included)
            if included.startswith("detail/"):
                problems.append(f"{where}: includes the core's internal {included}")
            elif included == own or included.startswith("mtpt/") or included not in VTK:
                continue  # the core's public headers; VTK's, the standard library's, generated
            elif VTK[included][0] == room:
                if VTK[included][1] >= rank:
                    problems.append(f"{where}: includes {included}, not before it in the room "
                                    f"{room}")
            elif VTK[included][0] not in ROOMS[room][2]:
                problems.append(f"{where}: the room {room} includes {included} of the room "
                                f"{VTK[included][0]}")
    return len(files)


def includes(path):
    with open(path, encoding="utf-8") as source:
        for number, line in enumerate(source, 1):
            match = INCLUDE.match(line)
            if match:
                yield number, match.group(1)


def check(source):
    problems = []
    count = check_core(os.path.join(source, "Core"), problems)
    count += check_vtk(os.path.join(source, "VTK"), problems)
    return count, problems


def self_test(source):
    """Each injected include must be reported by the check, and nothing else."""
    faults = [
        ("Core/mtpt/DepthKeys.h", '#include "mtpt/Decompose.h"', "a later stage"),
        ("Core/mtpt/Transform.h", '#include "mtpt/FramePipeline.h"', "layer 3"),
        ("Core/Culling.cxx", '#include "mtpt/LevelOfDetail.h"', "a later stage"),
        ("VTK/Input/MeshSource.h", '#include "Drawing/CPUBackend.h"', "the room input includes"),
        ("VTK/Drawing/BlendTarget.cxx", '#include "Drawing/CPUBackend.h"',
         "not before it in the room"),
        ("VTK/Drawing/CPUBackend.h", '#include "Drawing/OpenGLBackend.h"',
         "not before it in the room"),
        ("VTK/Reference/vtkMTPTReferenceRenderer.cxx", '#include "Drawing/RenderBackend.h"',
         "the room reference includes"),
        ("VTK/Drawing/RenderBackend.h", '#include "vtkMTPTReferenceRenderer.h"',
         "the room drawing includes"),
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
            caught = [p for p in found if p.startswith(relative) and expected in p]
            print(f"self-test: {line} in {relative}: "
                  f"{'reported' if caught and len(found) == 1 else 'NOT REPORTED ALONE'}")
            ok &= bool(caught) and len(found) == 1
    return ok


def main():
    args = [a for a in sys.argv[1:] if a != "--self-test"]
    here = os.path.dirname(os.path.abspath(__file__))
    source = args[0] if args else os.path.join(here, "..", "Source")
    if "--self-test" in sys.argv[1:]:
        return 0 if self_test(source) else 1
    count, problems = check(source)
    for problem in problems:
        print(problem)
    print(f"check-layers: {count} files, {len(problems)} includes running up, sideways or "
          f"into the core's internals, or of unknown place")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
