# SPDX-License-Identifier: BSD-3-Clause
"""The MTPT plugin in MPI-parallel pvbatch: the mesh distributed over the ranks, each rank
drawing its part with the MTPT mapper, and ParaView's ordered compositing blending them.

  pvbatch test_plugin_parallel.py PLUGIN DATA OUTPUT_DIR NAME [REFERENCE]
  mpiexec -n 2 pvbatch test_plugin_parallel.py PLUGIN DATA OUTPUT_DIR NAME REFERENCE

The mesh goes through RedistributeDataSet, and each rank's part is fetched and counted (and its
cells' ProcessId checked); every rank must hold a fair share of the cells.
Writes OUTPUT_DIR/NAME.png; with REFERENCE (the same script's image from one rank), checks
that the composited image matches it. Exits non-zero on failure.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mtpt_plugin_testing as testing  # noqa: E402
from paraview import servermanager, simple  # noqa: E402
from vtkmodules.util import numpy_support  # noqa: E402

# RMSE in [0, 1] RGB between the composited image and one rank's. Each rank sorts and blends
# only its own cells, then ParaView blends the ranks' images, so they may differ slightly
# where the parts meet.
MAX_RMSE_VS_ONE_RANK = 0.01
MIN_COVERED = 0.10

names = ["PLUGIN", "DATA", "OUTPUT_DIR", "NAME"]
args = testing.arguments(names)
positional = [a for a in sys.argv[1:] if not a.startswith("-")]
reference = positional[len(names)] if len(positional) > len(names) else None
image = os.path.join(args["OUTPUT_DIR"], args["NAME"] + ".png")


def main():
    ok = True

    testing.load_plugin(args["PLUGIN"])
    ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
    print("%s: %d MPI rank(s)" % (args["NAME"], ranks))

    reader = simple.XMLUnstructuredGridReader(FileName=[args["DATA"]])
    distributed = simple.RedistributeDataSet(Input=reader)

    # Cells per rank: each cell is given the rank that holds it (ProcessId), and each rank's
    # part is fetched on its own.
    if hasattr(simple, "ProcessIdScalars"):  # ParaView 5.11
        ids = simple.ProcessIdScalars(Input=distributed)
        ids.CellScalars = 1
        extra = []
    else:  # ParaView 6: ProcessIds; its "CellProcessIds" is the ProcessIds attribute, which
        # Fetch's MPI gather (VTK's legacy-writer marshalling) drops: copy it to "ProcessId".
        pids = simple.ProcessIds(Input=distributed, GeneratePointData=0, GenerateCellData=1)
        ids = simple.Calculator(Input=pids, AttributeType="Cell Data", Function="CellProcessIds",
                                ResultArrayName="ProcessId", ResultArrayType="Int")
        extra = [pids]
    counts = []
    for rank in range(ranks):
        part = servermanager.Fetch(ids, rank)
        holders = set(numpy_support.vtk_to_numpy(part.GetCellData().GetArray("ProcessId")).tolist())
        ok &= testing.check(part.GetNumberOfCells() == 0 or holders == {rank},
                            "the part fetched from rank %d is held by rank %d" % (rank, rank))
        counts.append(part.GetNumberOfCells())
    total = distributed.GetDataInformation().GetNumberOfCells()
    print("%s: cells per rank %s (total %d)" % (args["NAME"], counts, total))
    ok &= testing.check(sum(counts) == total, "every cell is held by one rank")
    ok &= testing.check(min(counts) >= total / (4 * ranks),
                        "every rank holds at least a quarter of its even share")
    simple.Delete(ids)
    for proxy in extra:
        simple.Delete(proxy)

    view = testing.make_view()
    display = testing.show_volume(distributed, view, testing.MTPT_REPRESENTATION)
    testing.save(view, image)
    representation_class, mapper_class = testing.active_mapper_class(display)
    ok &= testing.check(mapper_class == testing.MTPT_MAPPER_CLASS,
                        "representation %s draws with %s" % (representation_class, mapper_class))

    if reference:
        figures = testing.compare(image, reference)
        print("%s: %d ranks vs 1 rank: RMSE %.4f (covered pixels only: %.4f), volume covers "
              "%.1f%% / %.1f%% of the image" % (args["NAME"], ranks, figures["rmse"],
                                                figures["rmse_covered"], 100 * figures["covered_a"],
                                                100 * figures["covered_b"]))
        ok &= testing.check(figures["covered_a"] >= MIN_COVERED,
                            "image not blank (covered %.3f >= %.2f)" % (figures["covered_a"],
                                                                        MIN_COVERED))
        ok &= testing.check(figures["rmse"] <= MAX_RMSE_VS_ONE_RANK,
                            "RMSE vs 1 rank %.4f <= %.2f" % (figures["rmse"], MAX_RMSE_VS_ONE_RANK))
    return ok


testing.run(main, args["NAME"])
