// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshLoader.h
 * @brief Benchmark inputs from files: reads a VTK mesh, tetrahedralizes it and copies it into
 * the plain TetMesh the generator produces, so the core is timed on the same layout for
 * synthetic and real meshes. Compiled only when VTK is found.
 */
#ifndef mtpt_bench_MeshLoader_h
#define mtpt_bench_MeshLoader_h

#include "TetrahedralGrid.h"

#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <string>
#include <vector>

namespace mtpt
{
namespace bench
{

/**
 * Loads `fileName` (`.vtu`: VTK XML unstructured grid; `.vtk`: any legacy data set) into
 * `mesh`.
 * - Cells other than linear tetrahedra (hexahedra, quadratic tetrahedra, voxels of image
 *   data) are split with vtkDataSetTriangleFilter; cells of lower dimension are dropped.
 * - The scalar is the array `scalarName` (point data first, then cell data); an empty name
 *   takes the active point scalars, else the active cell scalars, else the first point
 *   array, else the first cell array. Vectors become their magnitude. Cell data is
 *   averaged to the points with vtkCellDataToPointData before the split, on the original
 *   cells, so a quadratic element weighs once per point and not once per sub-tetrahedron.
 * Returns false and sets `error` if the file cannot be read or yields no tetrahedra.
 */
bool LoadTetMesh(
  const std::string& fileName, const std::string& scalarName, TetMesh& mesh, std::string& error);

/// A real data set of the benchmark suite: a path relative to the data root and its scalar.
struct DataSetEntry
{
  const char* name;
  const char* relativePath;
  const char* scalarName; ///< empty: the active scalars
};

/// A vtkUnstructuredGrid of tetrahedra that uses the mesh's arrays in place (the mesh must
/// outlive it), with the scalars as active point scalars "scalars".
vtkSmartPointer<vtkUnstructuredGrid> ToUnstructuredGrid(const TetMesh& mesh);

/// The real meshes a data folder may hold (DataFolder.h), smallest first.
const std::vector<DataSetEntry>& SharedDataSets();

} // namespace bench
} // namespace mtpt

#endif
