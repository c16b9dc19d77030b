"""MTPT as the volume mapper of a PyVista plotter.

    import pyvista
    from mtpt.pyvista import add_volume

    plotter = pyvista.Plotter()
    actor = add_volume(plotter, grid, scalars="Density", cmap="viridis", opacity="sigmoid",
                       backend="cpu", shading_mode="pre-integrated")
    plotter.show()

``add_volume`` is ``pyvista.Plotter.add_volume`` with this package's mapper: PyVista itself
prepares the data set (point data from cell data, tetrahedra from other cells), the lookup
table, the colour and opacity transfer functions, the volume property and the scalar bar,
exactly as for its own mappers; then the volume's mapper is replaced by a
vtkMultiThreadedProjectedTetrahedraMapper with the same input and scalar selection.
Several add_volume calls in one plotter are drawn together, in one visibility order.
"""
import warnings

import pyvista

from . import vtkMultiThreadedProjectedTetrahedraMapper

try:  # PyVista's volume-mapper mix-in: lookup table, scalar range and data set properties
    from pyvista.plotting.mapper import _BaseVolumeMapper
except ImportError:  # pragma: no cover (a PyVista without it)
    _BaseVolumeMapper = None

__all__ = ["add_volume", "MultiThreadedProjectedTetrahedraMapper"]

_M = vtkMultiThreadedProjectedTetrahedraMapper
BACKENDS = {"automatic": _M.AUTOMATIC_BACKEND, "opengl": _M.OPENGL_BACKEND, "cpu": _M.CPU_BACKEND}
SHADING_MODES = {
    "vtk-compatible": _M.VTK_COMPATIBLE_SHADING,
    "pre-integrated": _M.PRE_INTEGRATED_SHADING,
}
# PyVista's names of vtkVolumeMapper's blend modes (Plotter.add_volume's `blending`).
BLEND_MODES = {
    "composite": 0, "comp": 0,
    "maximum": 1, "max": 1, "maximum-intensity": 1,
    "minimum": 2, "min": 2, "minimum-intensity": 2,
    "average": 3, "avg": 3, "average-intensity": 3,
    "additive": 4, "add": 4, "sum": 4,
}

if _BaseVolumeMapper is not None:

    class MultiThreadedProjectedTetrahedraMapper(_BaseVolumeMapper, _M):
        """vtkMultiThreadedProjectedTetrahedraMapper with PyVista's volume-mapper properties
        (``lookup_table``, ``scalar_range``, ``dataset``, ``blend_mode``), so the plotter's
        scalar bar and ``update_scalar_bar_range`` work with it as with PyVista's mappers."""

        def __init__(self, theme=None):
            super().__init__(theme=theme)

else:  # pragma: no cover

    class MultiThreadedProjectedTetrahedraMapper(_M):
        """vtkMultiThreadedProjectedTetrahedraMapper (this PyVista has no mapper mix-in)."""

        def __init__(self, theme=None):
            super().__init__()


def _choice(name, value, choices):
    if value is None:
        return None
    if isinstance(value, str):
        key = value.lower().replace("_", "-")
        if key in choices:
            return choices[key]
    elif value in choices.values():
        return value
    raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in choices)}, not {value!r}")


def _mapper_like(plotter, pyvista_mapper):
    """An MTPT mapper with the input, scalars and colouring of PyVista's mapper."""
    mapper = MultiThreadedProjectedTetrahedraMapper(theme=getattr(plotter, "_theme", None))
    if _BaseVolumeMapper is not None and isinstance(pyvista_mapper, _BaseVolumeMapper):
        mapper.lookup_table = pyvista_mapper.lookup_table
        mapper.scalar_range = pyvista_mapper.scalar_range
    mapper.SetInputDataObject(0, pyvista_mapper.GetInputDataObject(0, 0))
    mapper.SetScalarMode(pyvista_mapper.GetScalarMode())
    mapper.SetArrayAccessMode(pyvista_mapper.GetArrayAccessMode())
    if pyvista_mapper.GetArrayName():
        mapper.SelectScalarArray(pyvista_mapper.GetArrayName())
    else:
        mapper.SelectScalarArray(pyvista_mapper.GetArrayId())
    return mapper


def _replace_mapper(plotter, actor, old, new):
    """Every reference PyVista keeps to the mapper, from `old` to `new`: the actor, the
    plotter's current mapper (its scalar bar), and the scalar bars' mapper lists
    (update_scalar_bar_range)."""
    actor.SetMapper(new)
    if getattr(plotter, "mapper", None) is old:
        plotter.mapper = new
    scalar_bars = getattr(plotter, "scalar_bars", None)
    for mappers in getattr(scalar_bars, "_scalar_bar_mappers", {}).values():
        mappers[:] = [new if m is old else m for m in mappers]


def add_volume(plotter, volume, *, backend=None, shading_mode=None, image_sample_distance=None,
               number_of_threads=None, **kwargs):
    """Add a volume rendered by MTPT to a PyVista plotter; returns the volume actor.

    plotter
        A ``pyvista.Plotter`` (or any ``BasePlotter``).
    volume
        A ``pyvista.UnstructuredGrid``, or any data set PyVista can cast to one (image data,
        rectilinear and structured grids are cast first; PyVista then cuts every cell that
        is not a tetrahedron into tetrahedra).
    backend
        ``"automatic"`` (default: the CPU compositor where OpenGL is a software rasterizer),
        ``"opengl"`` or ``"cpu"``.
    shading_mode
        ``"vtk-compatible"`` (default) or ``"pre-integrated"`` (the transfer functions
        integrated exactly along each ray segment).
    image_sample_distance
        Composite at 1/d of the window's resolution on each side and stretch the image. A
        number turns its automatic adjustment off; ``None`` keeps the mapper's default, which
        adjusts the distance, with the fraction of the cells drawn, to the frame rate the
        interactor asks for while the view moves and renders still frames in full.
    number_of_threads
        Threads of the CPU stages; ``None`` or 0: every core.
    **kwargs
        The keyword arguments of ``pyvista.Plotter.add_volume``, with the same meaning and
        defaults: ``scalars``, ``clim``, ``cmap``, ``opacity``, ``n_colors``,
        ``flip_scalars``, ``show_scalar_bar``, ``scalar_bar_args``,
        ``opacity_unit_distance``, ``name``, ``reset_camera``, ``preference``,
        ``categories``, ``annotations``, ``log_scale``, ``pickable``, ``render``,
        ``user_matrix``, ``ambient``, ``diffuse``, ``specular``, ``specular_power``.
        ``mapper`` is not taken (this function chooses it). ``shade`` lights the volume by
        the renderer's lights with ``ambient``, ``diffuse``, ``specular`` and
        ``specular_power``, and ``blending`` takes PyVista's names of the five blend modes,
        both as VTK's GPU ray caster draws them.
    """
    if "mapper" in kwargs:
        raise TypeError("add_volume() chooses the mapper itself: leave out mapper=")
    # Set on MTPT's mapper below: PyVista's own unstructured-grid mapper takes only two modes.
    blending = _choice("blending", kwargs.pop("blending", "composite"), BLEND_MODES)
    backend = _choice("backend", backend, BACKENDS)
    shading_mode = _choice("shading_mode", shading_mode, SHADING_MODES)
    if image_sample_distance is not None and not image_sample_distance >= 1:
        raise ValueError(f"image_sample_distance must be at least 1, not {image_sample_distance!r}")
    if number_of_threads is not None and number_of_threads < 0:
        raise ValueError(f"number_of_threads must be 0 (every core) or more, not {number_of_threads!r}")

    volume = pyvista.wrap(volume)
    if not isinstance(volume, pyvista.UnstructuredGrid):
        if not hasattr(volume, "cast_to_unstructured_grid"):
            raise TypeError(f"add_volume() needs a data set with cells, not {type(volume).__name__}")
        volume = volume.cast_to_unstructured_grid()

    # PyVista builds everything for its own unstructured-grid mapper, without rendering.
    render = kwargs.pop("render", True)
    actor = plotter.add_volume(volume, render=False, **kwargs)
    if isinstance(actor, (list, tuple)):  # pragma: no cover (multi-block input)
        raise TypeError("add_volume() takes one data set; add the blocks one by one")
    pyvista_mapper = actor.GetMapper()
    mapper = _mapper_like(plotter, pyvista_mapper)
    if backend is not None:
        mapper.SetBackend(backend)
    if shading_mode is not None:
        mapper.SetShadingMode(shading_mode)
    if image_sample_distance is not None:
        mapper.AutoAdjustSampleDistancesOff()
        mapper.SetImageSampleDistance(float(image_sample_distance))
    if number_of_threads is not None:
        mapper.SetNumberOfThreads(int(number_of_threads))
    mapper.SetBlendMode(blending)

    _replace_mapper(plotter, actor, pyvista_mapper, mapper)
    if render:
        plotter.render()
    return actor
