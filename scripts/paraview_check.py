"""Opens a run's particle series with ParaView's XDMF3 reader and prints what ParaView sees: the
time steps, the points and cells of the last snapshot, every point array with its number of
components and range, and the bounds. A check that fields/particles.xdmf (2D or 3D) opens as
shockmpm means it to; the test suite reads the same files back without ParaView
(tests/test_output.cpp).

usage: pvpython --force-offscreen-rendering scripts/paraview_check.py OUT/fields/particles.xdmf
(pvpython: Debian's python3-paraview and paraview packages; not needed by anything else)
"""
import sys

from paraview.simple import Xdmf3ReaderS, servermanager

if len(sys.argv) != 2:
    sys.exit(__doc__)
reader = Xdmf3ReaderS(FileName=[sys.argv[1]])
reader.UpdatePipelineInformation()
times = reader.TimestepValues
print(f"time steps: {len(times)}, {times[0]:g} to {times[-1]:g} s")
reader.UpdatePipeline(times[-1])
data = servermanager.Fetch(reader)
block = data.GetBlock(0) if data.GetClassName() == "vtkMultiBlockDataSet" else data
print(f"last snapshot: {block.GetNumberOfPoints()} points, {block.GetNumberOfCells()} cells ({block.GetClassName()})")
arrays = block.GetPointData()
for i in range(arrays.GetNumberOfArrays()):
    a = arrays.GetArray(i)
    lo, hi = a.GetRange(-1 if a.GetNumberOfComponents() > 1 else 0)
    kind = "magnitude " if a.GetNumberOfComponents() > 1 else ""
    print(f"  {a.GetName():18s} {a.GetNumberOfComponents()} components, {kind}{lo:.6g} to {hi:.6g}")
print("bounds [m]:", " ".join(f"{b:.6g}" for b in block.GetBounds()))
