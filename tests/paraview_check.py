"""Run by ParaView's pvbatch (tests/test_paraview.py): open a results.pvd, go to the last time step,
Warp By Vector with the displacement, colour by a cell field, save a picture and print what ParaView
sees (number of time steps, bounds of the warped body, range of the field).

    pvbatch paraview_check.py RESULTS.pvd PICTURE.png FIELD
"""
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, PVDReader, Render,  # noqa
                             ResetCamera, SaveScreenshot, Show, WarpByVector)

src = PVDReader(FileName=sys.argv[1])
times = src.TimestepValues
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = times[-1]
warp = WarpByVector(Input=src)
warp.Vectors = ["POINTS", "displacement"]
view = GetActiveViewOrCreate("RenderView")
shown = Show(warp, view)
ColorBy(shown, ("CELLS", sys.argv[3]))
shown.RescaleTransferFunctionToDataRange(True, False)
shown.SetScalarBarVisibility(view, True)
view.InteractionMode = "2D"
ResetCamera(view)
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=[1200, 600])
warp.UpdatePipeline(times[-1])
b = warp.GetDataInformation().GetBounds()
lo, hi = warp.CellData[sys.argv[3]].GetRange()
print(f"PARAVIEW {len(times)} {b[0]!r} {b[1]!r} {b[2]!r} {b[3]!r} {lo!r} {hi!r}")
