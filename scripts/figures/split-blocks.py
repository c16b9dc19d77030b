#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Cuts an unstructured grid into a multi-block data set (.vtm) of interleaved parts: the
cells are sorted into SLABS slabs along an axis by their centres, and slab i goes to block
i % BLOCKS, so the blocks interpenetrate in depth wherever the view is oblique to the slabs.
A test scene for composite input (Examples/mtpt_render.cxx reads .vtm).

usage: scripts/figures/split-blocks.py INPUT.vtu OUTPUT.vtm [--blocks 2] [--slabs 6] [--axis 0]
Runs with Debian's python3 (python3-vtk9, which libvtk9-dev installs)."""
import argparse

from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkFiltersExtraction import vtkExtractCells
from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataWriter, vtkXMLUnstructuredGridReader

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("input")
parser.add_argument("output")
parser.add_argument("--blocks", type=int, default=2)
parser.add_argument("--slabs", type=int, default=6)
parser.add_argument("--axis", type=int, choices=(0, 1, 2), default=0)
args = parser.parse_args()

reader = vtkXMLUnstructuredGridReader()
reader.SetFileName(args.input)
reader.Update()
grid = reader.GetOutput()
if grid.GetNumberOfCells() == 0:
    raise SystemExit("split-blocks: %s has no cells" % args.input)
centres = vtkCellCenters()
centres.SetInputData(grid)
centres.Update()
points = centres.GetOutput().GetPoints()
low, high = grid.GetBounds()[2 * args.axis:2 * args.axis + 2]
width = (high - low) / args.slabs
cells = [vtkIdList() for _ in range(args.blocks)]
for c in range(grid.GetNumberOfCells()):
    slab = min(args.slabs - 1, int((points.GetPoint(c)[args.axis] - low) / width))
    cells[slab % args.blocks].InsertNextId(c)
tree = vtkMultiBlockDataSet()
tree.SetNumberOfBlocks(args.blocks)
for b in range(args.blocks):
    extract = vtkExtractCells()
    extract.SetInputData(grid)
    extract.SetCellList(cells[b])
    extract.Update()
    tree.SetBlock(b, extract.GetOutput())
writer = vtkXMLMultiBlockDataWriter()
writer.SetFileName(args.output)
writer.SetInputData(tree)
if writer.Write() != 1:
    raise SystemExit("split-blocks: could not write %s" % args.output)
print("split-blocks: %d cells into %d blocks of %s cells, written to %s" % (
    grid.GetNumberOfCells(), args.blocks, ", ".join(str(l.GetNumberOfIds()) for l in cells),
    args.output))
