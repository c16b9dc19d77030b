# SPDX-License-Identifier: BSD-3-Clause
"""Start-up script for ParaView's GUI (paraview --script=...), used by
scripts/figures/paraview-gui-figure.sh: loads the plugin, opens a mesh, shows it as the
"Multi-threaded projected tetra" representation coloured by Density, then writes a marker
file so that the caller knows the window is ready for its screenshot.

Environment: MTPT_PLUGIN (MTPT.so), MTPT_DATA (a .vtu with a point array Density),
MTPT_READY (the marker file to write)."""
import os

from paraview import simple

simple.LoadPlugin(os.environ["MTPT_PLUGIN"], remote=False, ns=globals())
reader = simple.XMLUnstructuredGridReader(registrationName=os.path.basename(os.environ["MTPT_DATA"]),
                                          FileName=[os.environ["MTPT_DATA"]])
view = simple.GetActiveViewOrCreate("RenderView")
display = simple.Show(reader, view)
display.SetRepresentationType("Multi-threaded projected tetra")
simple.ColorBy(display, ("POINTS", "Density"))
lut = simple.GetColorTransferFunction("Density")
for preset in ("Viridis (matplotlib)", "Viridis"):  # ParaView 5.11's name, then 6.1's
    try:
        lut.ApplyPreset(preset, True)
        break
    except RuntimeError:
        continue
opacity = simple.GetOpacityTransferFunction("Density")
opacity.Points = [0.19, 0.0, 0.5, 0.0, 4.98, 0.9, 0.5, 0.0]
display.ScalarOpacityUnitDistance = 1.0
display.SetScalarBarVisibility(view, True)
simple.SetActiveSource(reader)
view.ResetCamera()
camera = view.GetActiveCamera()
camera.Azimuth(30)
camera.Elevation(20)
view.ResetCamera()
simple.Render(view)
with open(os.environ["MTPT_READY"], "w") as ready:
    ready.write("ready\n")
