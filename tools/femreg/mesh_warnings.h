// Checks of a rest mesh that every command warns about: folded elements. Mesh readers
// re-orient negatively oriented tetrahedra (FinalizeMesh), which is right for a file with the
// other orientation convention but hides a fold: an element that overlaps its neighbour.
#ifndef FEMREG_TOOLS_MESH_WARNINGS_H_
#define FEMREG_TOOLS_MESH_WARNINGS_H_

#include <string>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/scene.h"

namespace femreg {
namespace cli {

// Elements (ascending) that lie on the same side of an interior face as the element across
// it: the two overlap, so the rest mesh is folded there. Positions: mesh.rest.
std::vector<int> FoldedElements(const TetMesh& mesh);

// Prints "femreg COMMAND: warning: WHAT has N folded rest element(s) (first: ...)" to stderr
// when there are any; returns their number.
int WarnFoldedElements(const std::string& command, const std::string& what, const TetMesh& mesh);

// The same for the mesh of every object of a scene ("object 'beam'"), and for a synth
// section's ground truth mesh file when it has one, for commands that do not load them
// themselves. A mesh that cannot be loaded is skipped: the command reports that error where
// it loads it. Returns the number of folded elements over all of them.
int WarnFoldedSceneMeshes(const std::string& command, const Scene& scene);

}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_MESH_WARNINGS_H_
