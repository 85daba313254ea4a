"""Mesh renders for the docs with VTK (Debian's python3-vtk9), off screen: real triangles with
a z-buffer, flat-shaded so that facets show as they are (no point splats, no speckles).

VTK needs an X display for its OpenGL context: `ensure_display()` re-runs the calling script
under `xvfb-run` (Debian's xvfb) when there is none."""
import os
import sys

import numpy as np


def ensure_display():
    if not os.environ.get("DISPLAY") and not os.environ.get("SDFCONTOUR_UNDER_XVFB"):
        os.environ["SDFCONTOUR_UNDER_XVFB"] = "1"
        os.execvp("xvfb-run", ["xvfb-run", "-a", sys.executable] + sys.argv)


def render(V, F, size=420, color=(0.62, 0.72, 0.86), azimuth=-35.0, elevation=20.0, zoom=1.25,
           edges=False):
    """An RGB image (size, size, 3) in [0, 1] of the mesh (V (n, 3), F (m, 3)), y up, seen from
    the front right and a little above, lit by a headlight and one key light; with `edges`, the
    triangles' edges drawn."""
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(V, dtype=np.float64), deep=True))
    cells = np.hstack([np.full((len(F), 1), 3), F]).astype(np.int64).ravel()
    polys = vtk.vtkCellArray()
    polys.SetCells(len(F), numpy_to_vtkIdTypeArray(cells, deep=True))
    mesh = vtk.vtkPolyData()
    mesh.SetPoints(points)
    mesh.SetPolys(polys)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(mesh)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetColor(*color)
    prop.SetInterpolationToFlat()
    prop.SetSpecular(0.15)
    if edges:
        prop.EdgeVisibilityOn()
        prop.SetEdgeColor(0.15, 0.2, 0.3)
        prop.SetLineWidth(0.6)
    renderer = vtk.vtkRenderer()
    renderer.AddActor(actor)
    renderer.SetBackground(1, 1, 1)
    camera = renderer.GetActiveCamera()
    camera.SetViewUp(0, 1, 0)
    camera.SetPosition(0, 0, 1)
    camera.SetFocalPoint(0, 0, 0)
    renderer.ResetCamera()
    camera.Azimuth(azimuth)
    camera.Elevation(elevation)
    camera.OrthogonalizeViewUp()
    renderer.ResetCamera()
    camera.Zoom(zoom)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(size, size)
    window.SetMultiSamples(8)
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    image = grab.GetOutput()
    w, h, _ = image.GetDimensions()
    rgb = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3]
    window.Finalize()
    return rgb / 255.0
