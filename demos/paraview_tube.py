"""The picture docs/img/tube.png, from the tube demo's results, made with ParaView's Python::

    xvfb-run -a pvpython demos/paraview_tube.py results/demo_tube/results.pvd docs/img/tube.png

The dented quarter at the last step, its displacement magnified five times, coloured by the
equivalent plastic strain (the cell averages the VTK writer stores)."""
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction,  # noqa
                             GetScalarBar, PVDReader, Render, SaveScreenshot, Show, WarpByVector)

src = PVDReader(FileName=sys.argv[1])
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = src.TimestepValues[-1]
warp = WarpByVector(Input=src)
warp.Vectors = ["POINTS", "displacement"]
warp.ScaleFactor = 5.0
view = GetActiveViewOrCreate("RenderView")
view.OrientationAxesVisibility = 1
shown = Show(warp, view)
shown.Representation = "Surface With Edges"
shown.EdgeColor = [0.3, 0.3, 0.3]
ColorBy(shown, ("CELLS", "plastic_strain_cell_avg"))
shown.RescaleTransferFunctionToDataRange(True, False)
shown.SetScalarBarVisibility(view, True)
GetColorTransferFunction("plastic_strain_cell_avg").ApplyPreset("Viridis (matplotlib)", True)
bar = GetScalarBar(GetColorTransferFunction("plastic_strain_cell_avg"), view)
bar.Title = "plastic strain"
bar.ComponentTitle = ""
bar.WindowLocation = "Any Location"
bar.Position = [0.84, 0.2]
bar.ScalarBarLength = 0.5
bar.TitleFontSize = 8
bar.LabelFontSize = 7
bar.ScalarBarThickness = 12
bar.TitleBold = 0
bar.HorizontalTitle = 1
bar.TextPosition = "Ticks left/bottom, annotations right/top"
bar.LabelFormat = "%.2f"
bar.RangeLabelFormat = "%.2f"
Render(view)
view.CameraPosition = [48.0, 62.0, -38.0]
view.CameraFocalPoint = [0.0, 18.0, 22.0]
view.CameraViewUp = [0.0, 1.0, 0.0]
view.CameraViewAngle = 45.0
Render(view)
SaveScreenshot(sys.argv[2], view, ImageResolution=[1200, 700])
