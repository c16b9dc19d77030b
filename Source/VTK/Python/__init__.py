"""MTPT: multi-threaded projected tetrahedra volume mapper for VTK.

    from mtpt import vtkMultiThreadedProjectedTetrahedraMapper
"""
from .vtkRenderingMTPT import *  # noqa: F401,F403
