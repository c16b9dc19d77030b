#!/usr/bin/env python3
"""Volume-render an unstructured grid with MTPT from PyVista.

    python3 Examples/pyvista_volume.py [mesh.vtu] [--scalars NAME] [--cmap NAME]
        [--opacity NAME] [--backend automatic|opengl|cpu]
        [--shading vtk-compatible|pre-integrated] [--screenshot FILE.png]

Without --screenshot it opens an interactive window (drag to turn the volume: while it
moves, the mapper draws at a coarser image sample distance to keep up, and in full when
it stops). Needs PyVista and the mtpt package (pip install <this checkout>).
"""
import argparse
import os
import time

import pyvista

from mtpt.pyvista import add_volume

DEFAULT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Data", "bluntfin_tets.vtu")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", nargs="?", default=DEFAULT, help="a file PyVista reads (default: the blunt fin)")
    parser.add_argument("--scalars", help="point or cell array to draw (default: the active scalars)")
    parser.add_argument("--cmap", default="viridis")
    parser.add_argument("--opacity", default="linear", help="PyVista's opacity name, e.g. linear, sigmoid, geom")
    parser.add_argument("--opacity-unit-distance", type=float, default=0.4,
                        help="length over which the opacity applies (PyVista's default for grids: 1)")
    parser.add_argument("--backend", default="automatic", choices=["automatic", "opengl", "cpu"])
    parser.add_argument("--shading", default="vtk-compatible", choices=["vtk-compatible", "pre-integrated"])
    parser.add_argument("--size", default="800x600", help="window size, WIDTHxHEIGHT")
    parser.add_argument("--screenshot", help="render off-screen into this PNG file and exit")
    args = parser.parse_args()

    mesh = pyvista.read(args.mesh)
    width, height = (int(v) for v in args.size.lower().split("x"))
    plotter = pyvista.Plotter(off_screen=bool(args.screenshot), window_size=(width, height))
    plotter.background_color = (0.1, 0.1, 0.2)
    actor = add_volume(plotter, mesh, scalars=args.scalars, cmap=args.cmap, opacity=args.opacity,
                       opacity_unit_distance=args.opacity_unit_distance, backend=args.backend,
                       shading_mode=args.shading)
    plotter.camera_position = "xy"
    plotter.camera.azimuth = 30
    plotter.camera.elevation = 20
    plotter.reset_camera()
    plotter.camera.zoom(1.5)
    plotter.add_text(f"MTPT in PyVista {pyvista.__version__}: {mesh.n_cells:,} cells",
                     font_size=10, position="upper_left")
    if args.screenshot:
        started = time.perf_counter()
        plotter.screenshot(args.screenshot)
        mapper = actor.GetMapper()
        print(f"{args.screenshot}: {mesh.n_cells} cells, first frame {time.perf_counter() - started:.2f} s "
              f"(backend {mapper.GetLastBackend()}, {mapper.GetNumberOfThreads() or 'every'} threads)")
    else:
        plotter.show()


if __name__ == "__main__":
    main()
