# SPDX-License-Identifier: BSD-3-Clause
"""The MTPT plugin in client-server mode: pvpython connected to an MPI-parallel pvserver,
the plugin loaded on both sides (as in the GUI: Tools > Manage Plugins, client and server).

  mpiexec -n 2 pvserver --server-port=PORT &
  pvpython test_plugin_client_server.py PLUGIN DATA OUTPUT_DIR NAME PORT REFERENCE

Shows the mesh, distributed over the server's ranks, with the MTPT representation, writes
OUTPUT_DIR/NAME.png and compares it with REFERENCE (test_plugin_parallel.py's 1-rank image).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mtpt_plugin_testing as testing  # noqa: E402
from paraview import servermanager, simple  # noqa: E402

MAX_RMSE_VS_ONE_RANK = 0.01  # as test_plugin_parallel.py
MIN_COVERED = 0.10

args = testing.arguments(["PLUGIN", "DATA", "OUTPUT_DIR", "NAME", "PORT", "REFERENCE"])
image = os.path.join(args["OUTPUT_DIR"], args["NAME"] + ".png")


def main():
    ok = True
    simple.Connect("localhost", int(args["PORT"]))
    ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
    ok &= testing.check(ranks == 2, "connected to pvserver with %d ranks" % ranks)
    simple.LoadPlugin(args["PLUGIN"], remote=True, ns=globals())   # on the server
    simple.LoadPlugin(args["PLUGIN"], remote=False, ns=globals())  # on the client

    reader = simple.XMLUnstructuredGridReader(FileName=[args["DATA"]])
    distributed = simple.RedistributeDataSet(Input=reader)
    view = testing.make_view()
    display = testing.show_volume(distributed, view, testing.MTPT_REPRESENTATION)
    testing.save(view, image)
    representation_class, mapper_class = testing.active_mapper_class(display)
    ok &= testing.check(mapper_class == testing.MTPT_MAPPER_CLASS,
                        "client's representation %s draws with %s" % (representation_class,
                                                                       mapper_class))

    figures = testing.compare(image, args["REFERENCE"])
    print("%s: pvserver (%d ranks) vs 1 rank: RMSE %.4f (covered pixels only: %.4f)"
          % (args["NAME"], ranks, figures["rmse"], figures["rmse_covered"]))
    ok &= testing.check(figures["covered_a"] >= MIN_COVERED,
                        "image not blank (covered %.3f >= %.2f)" % (figures["covered_a"],
                                                                    MIN_COVERED))
    ok &= testing.check(figures["rmse"] <= MAX_RMSE_VS_ONE_RANK,
                        "RMSE vs 1 rank %.4f <= %.2f" % (figures["rmse"], MAX_RMSE_VS_ONE_RANK))
    simple.Disconnect()
    return ok


testing.run(main, args["NAME"])
