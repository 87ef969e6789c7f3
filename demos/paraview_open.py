"""What ParaView sees in a run's fields.xdmf: run with ParaView's pvpython (not the project's venv).

    pvpython demos/paraview_open.py results/copper_wire/fields.xdmf

Debian 12's ParaView 5.11 in a bookworm root (the XDMF3 reader, as the GUI opens it):
    ../shared/tools/debian-suite-run --suite bookworm --install "paraview python3-paraview" -- \\
        'OMPI_MCA_btl=self,vader pvpython demos/paraview_open.py results/copper_wire/fields.xdmf'
Measured on Example 1 (h = 0.25): one vtkUnstructuredGrid, 5001 points, 1200 cells, the point arrays
velocity, equivalent_strain_rate, hydrostatic_pressure, secant_viscosity (before: a
vtkMultiBlockDataSet of five grids over the same mesh).
"""
import sys

from paraview.simple import OpenDataFile, servermanager

reader = OpenDataFile(sys.argv[1])
reader.UpdatePipeline()
data = servermanager.Fetch(reader)
print(f"reader {reader.GetXMLName()}: {data.GetClassName()}, {data.GetNumberOfPoints()} points, "
      f"{data.GetNumberOfCells()} cells")
if hasattr(data, "GetPointData"):
    arrays = data.GetPointData()
    for i in range(arrays.GetNumberOfArrays()):
        print(f"  {arrays.GetArrayName(i)}: range {arrays.GetArray(i).GetRange()}")
