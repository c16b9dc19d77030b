#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks that no file of the core (Source/Core) includes a header of a higher layer
(Documentation/architecture.md, "The stages of a frame"). From the lowest:
  0  vocabulary: mtpt/MeshView.h, Records.h, Shading.h, Stage.h, Threads.h, Timing.h,
     TransferFunctionTable.h
  1  helpers: detail/*.h
  2  stages: mtpt/Transform.h, Culling.h, LevelOfDetail.h, DepthKeys.h, NearPlane.h,
     VisibilityOrder.h, Decompose.h (a stage may include an earlier one)
  3  assemblies: mtpt/Compositor.h, FramePipeline.h, ReferenceRenderer.h, ImageSampling.h
A source file belongs to the layer of the header it implements. Exit status 1 with one line
per upward include; a header that the table does not know is an error too.

usage: scripts/check-layers.py [SOURCE-CORE-DIR]   (default: Source/Core beside this script)"""
import os
import re
import sys

LAYERS = {
    "mtpt/MeshView.h": 0, "mtpt/Records.h": 0, "mtpt/Shading.h": 0, "mtpt/Stage.h": 0,
    "mtpt/Threads.h": 0, "mtpt/Timing.h": 0, "mtpt/TransferFunctionTable.h": 0,
    "mtpt/Transform.h": 2, "mtpt/Culling.h": 2, "mtpt/LevelOfDetail.h": 2,
    "mtpt/DepthKeys.h": 2, "mtpt/NearPlane.h": 2,
    "mtpt/VisibilityOrder.h": 2, "mtpt/Decompose.h": 2,
    "mtpt/Compositor.h": 3, "mtpt/FramePipeline.h": 3, "mtpt/ReferenceRenderer.h": 3,
    "mtpt/ImageSampling.h": 3,
}
# Sources whose header is not named after them.
SOURCE_HEADERS = {"TileRaster.cxx": "detail/TileRaster.h",
                  "DecomposeBatch.cxx": "detail/DecomposeBatch.h",
                  "KeyBatch.cxx": "detail/KeyBatch.h"}


def layer(header):
    if header.startswith("detail/"):
        return 1
    if header not in LAYERS:
        raise KeyError(header)
    return LAYERS[header]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    core = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "Source", "Core")
    problems = []
    files = []
    for folder in ("mtpt", "detail", ""):
        directory = os.path.join(core, folder)
        for name in sorted(os.listdir(directory)):
            if name.endswith((".h", ".cxx")):
                files.append(os.path.join(folder, name) if folder else name)
    for name in files:
        if name.endswith(".cxx"):
            own = SOURCE_HEADERS.get(name, "mtpt/" + name[:-4] + ".h")
        else:
            own = name
        try:
            own_layer = layer(own)
        except KeyError:
            problems.append(f"{name}: its layer is unknown (add {own} to LAYERS)")
            continue
        with open(os.path.join(core, name), encoding="utf-8") as source:
            for number, line in enumerate(source, 1):
                match = re.match(r'\s*#\s*include\s+"((?:mtpt|detail)/[^"]+)"', line)
                if not match or match.group(1) == own:
                    continue
                try:
                    included = layer(match.group(1))
                except KeyError:
                    problems.append(f"{name}:{number}: {match.group(1)} has no layer")
                    continue
                if included > own_layer:
                    problems.append(f"{name}:{number}: includes {match.group(1)} (layer "
                                    f"{included}) from layer {own_layer}")
    for problem in problems:
        print(problem)
    print(f"check-layers: {len(files)} files, {len(problems)} upward includes or unknown layers")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
