#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Blend modes against VTK's GPU ray caster: the wavelet as image data through
vtkGPUVolumeRayCastMapper and tetrahedralized through MTPT (both backends), in each of
vtkVolumeMapper's blend modes 1 to 4 (maximum, minimum and average intensity, additive), and
the exact reference in the same mode. Prints each MTPT image's covered-pixel RMSE against the
ray cast and against the reference (of 255), and VTK's PT's (it composites whatever the
mode); then the CPU backend's frame time in each mode against composite frames, the camera
turning before every frame, with the time of the order stage; and writes a picture: a column
per mode, VTK's GPU ray cast below, MTPT (CPU backend) above.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/blend-modes.py
         [--size 400] [--extent 20] [--frames 7] [--picture blend_modes.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless)."""
import argparse
import statistics
import time

from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=400)
parser.add_argument("--extent", type=int, default=20, help="wavelet extent: -E..E per axis")
parser.add_argument("--frames", type=int, default=7, help="timed frames per measurement")
parser.add_argument("--picture", default="blend_modes.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)
MODES = (("maximum", 1), ("minimum", 2), ("average", 3), ("additive", 4))
AVERAGE_RANGE = (120.0, 240.0)


def volume_property():
    prop = figures.volume_property(
        colours=((40, 0.2, 0.3, 0.9), (160, 0.95, 0.95, 0.6), (280, 0.9, 0.2, 0.1)),
        opacities=((40, 0.05), (120, 0.3), (280, 0.9)), unit_distance=40.0)
    prop.SetInterpolationTypeToLinear()
    return prop


def scene(data, mapper, mode):
    mapper.SetBlendMode(mode)
    if hasattr(mapper, "SetAverageIPScalarRange"):  # VTK's PT has none
        mapper.SetAverageIPScalarRange(*AVERAGE_RANGE)
    renderer, volume = figures.volume_scene(data, mapper, volume_property(), BACKGROUND)
    return renderer, volume, figures.window_for(renderer, args.size)



image_data, grid = figures.wavelet(args.extent)
print(f"wavelet: {grid.GetNumberOfCells()} tetrahedra, {args.size}x{args.size}, VTK's default "
      f"window (multisampled); average intensity over scalars {AVERAGE_RANGE}")
columns = []
for name, mode in MODES:
    renderer, volume, window = scene(image_data, figures.gpu_ray_cast(), mode)
    window.Render()
    ray_image = figures.grab(window)
    for backend in ("CPU", "OpenGL"):
        renderer, volume, window = scene(grid, figures.mtpt_mapper(backend), mode)
        window.Render()
        image = figures.grab(window)
        exact = figures.reference(renderer, volume)
        ray, _ = figures.difference(image, ray_image, BACKGROUND, 255)
        ref, worst = figures.difference(image, exact, BACKGROUND, 255)
        print(f"{name:8s} MTPT {backend:6s}: covered RMSE against VTK's GPU ray cast "
              f"{ray:.1f}/255, against the exact reference {ref:.2f}/255 (worst {worst:.0f})")
        if backend == "CPU":
            columns.append(figures.append([ray_image, image], 1))
    renderer, volume, window = scene(grid, vtkProjectedTetrahedraMapper(), mode)
    window.Render()
    rmse, _ = figures.difference(figures.grab(window), ray_image, BACKGROUND, 255)
    print(f"{name:8s} VTK's PT (composites whatever the mode): covered RMSE against VTK's GPU "
          f"ray cast {rmse:.1f}/255")

print(f"\nFrame time, MTPT CPU backend, the camera turning 2 degrees before each frame "
      f"(median of {args.frames} frames):")
composite = None
for name, mode in (("composite", 0),) + MODES:
    m = figures.mtpt_mapper("CPU")
    renderer, volume, window = scene(grid, m, mode)
    window.Render()
    seconds, order = [], []
    for _ in range(args.frames):
        renderer.GetActiveCamera().Azimuth(2)
        start = time.perf_counter()
        window.Render()
        seconds.append(time.perf_counter() - start)
        order.append(m.GetOrderSeconds())
    frame = statistics.median(seconds)
    composite = composite or frame
    print(f"  {name:9s}: {1e3 * frame:6.1f} ms ({frame / composite:.2f}x composite), order "
          f"stage {1e3 * statistics.median(order):.1f} ms")

figures.write_picture(args.picture, columns, 0)
print(f"\nwrote {args.picture}: a column per mode (maximum, minimum, average, additive), VTK's "
      "GPU ray cast of the image data below, MTPT (CPU backend) above")
