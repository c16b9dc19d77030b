"""MTPT: multi-threaded projected tetrahedra volume mapper for VTK.

    from mtpt import vtkMultiThreadedProjectedTetrahedraMapper

The package is compiled against one VTK. Importing it next to another VTK (another
version, or a second copy of the same version such as a pip wheel beside the system's)
would load two VTKs into one process, so the import checks first and raises ImportError
with what to do instead.
"""
import os as _os

from ._build import VTK_COMMON_CORE as _BUILT_CORE
from ._build import VTK_VERSION as _BUILT_VERSION


def _check_vtk():
    try:
        import vtkmodules
        from vtkmodules.vtkCommonCore import vtkVersion
    except ImportError as error:
        raise ImportError(
            f"mtpt needs VTK {_BUILT_VERSION}'s Python modules (vtkmodules), which this "
            f"Python cannot import: {error}") from error
    running = vtkVersion.GetVTKVersion()
    where = _os.path.dirname(vtkmodules.__file__)
    if running.split(".")[:2] != _BUILT_VERSION.split(".")[:2]:
        raise ImportError(
            f"mtpt was built against VTK {_BUILT_VERSION}, but this Python imports VTK "
            f"{running} (from {where}). Build mtpt against this VTK (pip install "
            f"--no-cache-dir --force-reinstall <mtpt source>, with that VTK's CMake package "
            f"found through VTK_DIR or CMAKE_PREFIX_PATH), or run the Python whose VTK it "
            f"was built against.")
    # The same version from another place (e.g. a pip wheel beside the system's VTK):
    # the extension would load the VTK it was linked against in addition to this one.
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
            loaded = {line.split(None, 5)[-1].strip() for line in maps if "libvtkCommonCore" in line}
    except OSError:
        return
    loaded = {_os.path.realpath(path) for path in loaded if path.startswith("/")}
    built = _os.path.realpath(_BUILT_CORE)
    if loaded and built not in loaded:
        raise ImportError(
            f"mtpt was linked against the VTK in {_os.path.dirname(built)}, but this Python "
            f"has loaded VTK {running} from {', '.join(sorted(loaded))} (vtkmodules in "
            f"{where}); two VTKs cannot share a process. Build mtpt against the VTK this "
            f"Python imports, or import the VTK it was built against.")


_check_vtk()
del _check_vtk

from .vtkRenderingMTPT import *  # noqa: E402,F401,F403
