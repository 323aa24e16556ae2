#include "mesh_warnings.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <iostream>
#include <utility>

#include "femreg/io.h"

namespace femreg {
namespace cli {

std::vector<int> FoldedElements(const TetMesh& mesh) {
  // Every element's faces (sorted vertices), its fourth vertex and the element, sorted by face
  // and then element: each later element with a face is compared with the first one met.
  // A sort, not a map: a map took a scan's 128k elements 0.2 s at every command's start.
  struct Face {
    std::array<int, 3> key;
    int element;
    int apex;
  };
  std::vector<Face> faces;
  faces.reserve(4 * static_cast<size_t>(mesh.num_tets()));
  static const int kFace[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};
  for (int t = 0; t < mesh.num_tets(); ++t) {
    for (const auto& f : kFace) {
      std::array<int, 3> key = {mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
      std::sort(key.begin(), key.end());
      faces.push_back({key, t, mesh.tets(t, f[3])});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
    return a.key != b.key ? a.key < b.key : a.element < b.element;
  });
  std::vector<char> folded(static_cast<size_t>(mesh.num_tets()), 0);
  for (size_t first = 0; first < faces.size();) {
    size_t next = first + 1;
    for (; next < faces.size() && faces[next].key == faces[first].key; ++next) {
      const std::array<int, 3>& key = faces[first].key;
      const Eigen::Vector3d a = mesh.rest.row(key[0]), b = mesh.rest.row(key[1]),
                            c = mesh.rest.row(key[2]);
      const Eigen::Vector3d n = (b - a).cross(c - a);
      const double s1 = n.dot(Eigen::Vector3d(mesh.rest.row(faces[first].apex)) - a);
      const double s2 = n.dot(Eigen::Vector3d(mesh.rest.row(faces[next].apex)) - a);
      if (s1 * s2 > 0) {  // both apexes on the same side: the elements overlap
        folded[static_cast<size_t>(faces[next].element)] = 1;
        folded[static_cast<size_t>(faces[first].element)] = 1;
      }
    }
    first = next;
  }
  std::vector<int> out;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    if (folded[static_cast<size_t>(t)]) out.push_back(t);
  }
  return out;
}

int WarnFoldedElements(const std::string& command, const std::string& what, const TetMesh& mesh) {
  const std::vector<int> folded = FoldedElements(mesh);
  if (folded.empty()) return 0;
  std::cerr << "femreg " << command << ": warning: " << what << " has " << folded.size()
            << " folded rest element(s) overlapping a neighbour (first:";
  for (size_t i = 0; i < folded.size() && i < 10; ++i) std::cerr << " " << folded[i];
  std::cerr << "); the results there are not meaningful: fix the mesh (femreg info lists them)\n";
  return static_cast<int>(folded.size());
}

int WarnFoldedSceneMeshes(const std::string& command, const Scene& scene) {
  int folded = 0;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    TetMesh mesh;
    if (!LoadObjectMesh(scene, static_cast<int>(i), &mesh).ok()) continue;
    folded += WarnFoldedElements(command, "object '" + scene.objects[i].name + "'", mesh);
  }
  // The object's scale and pose, which apply to this mesh too, keep every fold (an invertible
  // affine map keeps which side of a face a vertex is on): reading the file is enough.
  if (scene.synth.enabled && !scene.synth.mesh_path.empty()) {
    TetMesh truth;
    if (ReadTetMesh(scene.synth.mesh_path, &truth).ok()) {
      folded += WarnFoldedElements(command, "the ground truth mesh " + scene.synth.mesh_path, truth);
    }
  }
  return folded;
}

}  // namespace cli
}  // namespace femreg
