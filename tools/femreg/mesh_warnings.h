// Checks of a rest mesh that every command warns about: folded elements. Mesh readers
// re-orient negatively oriented tetrahedra (FinalizeMesh), which is right for a file with the
// other orientation convention but hides a fold: an element that overlaps its neighbour.
#ifndef FEMREG_TOOLS_MESH_WARNINGS_H_
#define FEMREG_TOOLS_MESH_WARNINGS_H_

#include <string>
#include <vector>

#include "femreg/mesh.h"

namespace femreg {
namespace cli {

// Elements (ascending) that lie on the same side of an interior face as the element across
// it: the two overlap, so the rest mesh is folded there. Positions: mesh.rest.
std::vector<int> FoldedElements(const TetMesh& mesh);

// Prints "femreg COMMAND: warning: WHAT has N folded rest element(s) (first: ...)" to stderr
// when there are any; returns their number.
int WarnFoldedElements(const std::string& command, const std::string& what, const TetMesh& mesh);

}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_MESH_WARNINGS_H_
