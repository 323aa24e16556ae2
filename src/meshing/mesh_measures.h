// The measures of a finished tetrahedral mesh that femreg mesh reports (private to
// src/meshing/).
#ifndef FEMREG_MESHING_MESH_MEASURES_H_
#define FEMREG_MESHING_MESH_MEASURES_H_

#include <string>

#include "femreg/mesh.h"
#include "femreg/meshing.h"

namespace femreg {
namespace internal {

// Fills the report's mesh part: counts, regions, volume, quality, the edge lengths and the
// shares of tetrahedra with a dihedral angle below 10 or above 170 degrees.
void MeasureMesh(const TetMesh& mesh, MeshingReport* report);

// A number in messages and reports: six significant digits.
std::string Fmt(double v);

// The smallest and largest dihedral angles of tetrahedron t (degrees).
void DihedralRange(const TetMesh& mesh, int t, double* min_deg, double* max_deg);

}  // namespace internal
}  // namespace femreg

#endif  // FEMREG_MESHING_MESH_MEASURES_H_
