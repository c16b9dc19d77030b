#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""A translucent sphere inside a volume, the renderer peeling volumes with its translucent
geometry (SetUseDepthPeeling, SetUseDepthPeelingForVolumes): the wavelet tetrahedralized and
drawn by MTPT (both backends), the same wavelet as image data drawn by VTK's GPU ray caster
(which takes part in depth peeling), VTK's PT, and the exact reference (the tetrahedra and the
sphere's triangles). Prints each image's covered-pixel RMSE and worst pixel against the
reference; then, with nested translucent spheres (two layers each) so that every peel allowed
is taken, the frame time against the renderer's maximum number of peels for MTPT (both
backends) and VTK's GPU ray cast (camera turning 1 degree before every frame); and writes a
picture: MTPT, VTK's GPU ray cast, VTK's PT, the reference.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/depth-peeling.py
         [--size 300] [--extent 10] [--frames 5] [--spheres 8] [--picture depth_peeling.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless).
VTK's depth peeling needs a single-sampled window: in a multisampled one (VTK's default)
VTK 9.1 on Mesa draws no translucent geometry at all, volumes or not."""
import argparse
import statistics
import time

from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper
import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=300)
parser.add_argument("--extent", type=int, default=10, help="wavelet extent: -E..E per axis")
parser.add_argument("--frames", type=int, default=5, help="timed frames per peel count")
parser.add_argument("--spheres", type=int, default=8,
                    help="nested translucent spheres in the timed scenes")
parser.add_argument("--picture", default="depth_peeling.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)


def volume_property():
    prop = figures.volume_property(
        colours=((40, 0.2, 0.3, 0.9), (160, 0.95, 0.95, 0.6), (280, 0.9, 0.2, 0.1)),
        opacities=((40, 0.0), (120, 0.05), (280, 0.6)), unit_distance=3.0)
    prop.SetInterpolationTypeToLinear()
    return prop


def scene(data, mapper, spheres=1):
    renderer, volume = figures.volume_scene(data, mapper, volume_property(), BACKGROUND)
    for k in range(spheres):
        sphere = vtkSphereSource()
        sphere.SetCenter(1.5, 1.0, 0.5)
        sphere.SetRadius(0.45 * args.extent * (1.0 - 0.5 * k / spheres))
        sphere.SetThetaResolution(64)
        sphere.SetPhiResolution(64)
        sphere_mapper = vtkPolyDataMapper()
        sphere_mapper.SetInputConnection(sphere.GetOutputPort())
        actor = vtkActor()
        actor.SetMapper(sphere_mapper)
        actor.GetProperty().SetColor(0.15, 0.85, 0.35)
        actor.GetProperty().SetOpacity(0.4 if spheres == 1 else 0.15)
        actor.GetProperty().LightingOff()
        renderer.AddActor(actor)
    renderer.SetUseDepthPeeling(1)
    renderer.SetUseDepthPeelingForVolumes(1)
    renderer.SetMaximumNumberOfPeels(8)
    renderer.SetOcclusionRatio(0.0)
    return renderer, volume, figures.window_for(renderer, args.size, multisamples=0)


image_data, grid = figures.wavelet(args.extent)
print(f"wavelet: {grid.GetNumberOfCells()} tetrahedra; {args.size}x{args.size}, sphere inside, "
      "depth peeling for volumes, single-sampled window")
images = {}
exact = None
contenders = [("MTPT (CPU backend)", grid, lambda: cpu_mapper()),
              ("MTPT (OpenGL backend)", grid, lambda: gl_mapper()),
              ("VTK's GPU ray cast of the image data", image_data, figures.gpu_ray_cast),
              ("VTK's PT", grid, lambda: vtkProjectedTetrahedraMapper())]


def cpu_mapper():
    m = Mapper()
    m.SetBackendToCPU()
    return m


def gl_mapper():
    m = Mapper()
    m.SetBackendToOpenGL()
    return m


for name, data, make in contenders:
    renderer, volume, window = scene(data, make())
    window.Render()
    window.Render()
    images[name] = figures.grab(window)
    if exact is None:
        exact = figures.reference(renderer, volume)
    rmse, worst = figures.difference(images[name], exact, BACKGROUND)
    print(f"{name:38s} against the reference: covered RMSE {rmse:.4f}, worst {worst:.3f}")

print(f"\nFrame time against the renderer's maximum number of peels, {args.spheres} nested "
      f"translucent spheres inside the volume (median of {args.frames} frames, camera turning "
      "1 degree before each):")
print("| peels | MTPT, CPU backend | MTPT, OpenGL backend | VTK's GPU ray cast (image data) |")
print("|---:|---:|---:|---:|")
for peels in (0, 1, 2, 4, 8):
    row = []
    for data, make in ((grid, cpu_mapper), (grid, gl_mapper),
                       (image_data, figures.gpu_ray_cast)):
        renderer, volume, window = scene(data, make(), args.spheres)
        renderer.SetUseDepthPeeling(1 if peels > 0 else 0)
        renderer.SetUseDepthPeelingForVolumes(1 if peels > 0 else 0)
        renderer.SetMaximumNumberOfPeels(max(1, peels))
        window.Render()
        times = []
        for _ in range(args.frames):
            renderer.GetActiveCamera().Azimuth(1)
            start = time.perf_counter()
            window.Render()
            times.append(1000 * (time.perf_counter() - start))
        row.append(statistics.median(times))
    print(f"| {peels if peels else 'none'} | " + " | ".join(f"{t:.0f} ms" for t in row) + " |")

figures.write_picture(args.picture, [images[name] for name in (
    "MTPT (CPU backend)", "VTK's GPU ray cast of the image data", "VTK's PT")] + [exact], 0)
print(f"\nwrote {args.picture}: MTPT (CPU backend), VTK's GPU ray cast of the image data, "
      "VTK's PT, the exact reference")
