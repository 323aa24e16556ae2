// femreg info MESH [--json]: counts, volume, bounding box and element quality of a mesh.
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "mesh_warnings.h"

namespace femreg {
namespace cli {
namespace {

struct InfoOptions {
  std::string mesh_path;
  bool json = false;
};


std::string JsonIntList(const std::vector<int>& values) {
  std::ostringstream os;
  os << "[";
  for (size_t i = 0; i < values.size(); ++i) os << (i ? ", " : "") << values[i];
  os << "]";
  return os.str();
}

void RunInfo(const InfoOptions& options) {
  TetMesh mesh;
  const Status status = ReadTetMesh(options.mesh_path, &mesh);
  if (!status.ok()) {
    std::cerr << "femreg info: " << status.message() << "\n";
    SetExitCode(1);
    return;
  }
  const MeshFormat format = DetectMeshFormat(options.mesh_path);
  std::map<int, int> per_region;
  for (int t = 0; t < mesh.num_tets(); ++t) ++per_region[mesh.region(t)];
  const Eigen::Vector3d lo = mesh.rest.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = mesh.rest.colwise().maxCoeff().transpose();
  const double volume = RestVolume(mesh);
  const MeshQuality q = ComputeQuality(mesh, mesh.rest);
  // Readers re-orient inverted elements, so num_inverted is 0 for a file; a fold shows as
  // elements overlapping across a shared face.
  std::vector<int> folded = FoldedElements(mesh);
  const int num_folded = static_cast<int>(folded.size());
  if (folded.size() > 100) folded.resize(100);

  std::ostringstream os;
  os << std::setprecision(6);
  if (options.json) {
    os << "{\n  \"file\": " << JsonString(options.mesh_path) << ",\n"
       << "  \"format\": " << JsonString(ToString(format)) << ",\n"
       << "  \"vertices\": " << mesh.num_vertices() << ",\n"
       << "  \"elements\": " << mesh.num_tets() << ",\n"
       << "  \"surface_triangles\": " << mesh.num_surface_triangles() << ",\n"
       << "  \"surface_vertices\": " << mesh.surface_vertices.size() << ",\n"
       << "  \"regions\": {";
    bool first = true;
    for (const auto& r : per_region) {
      os << (first ? "" : ", ") << "\"" << r.first << "\": " << r.second;
      first = false;
    }
    os << "},\n  \"volume\": " << volume << ",\n"
       << "  \"bounding_box\": {\"min\": [" << lo.x() << ", " << lo.y() << ", " << lo.z()
       << "], \"max\": [" << hi.x() << ", " << hi.y() << ", " << hi.z() << "]},\n"
       << "  \"quality\": {\"min_dihedral_deg\": " << q.min_dihedral_deg
       << ", \"max_dihedral_deg\": " << q.max_dihedral_deg
       << ", \"max_aspect_ratio\": " << q.max_aspect_ratio
       << ", \"mean_aspect_ratio\": " << q.mean_aspect_ratio << "},\n"
       << "  \"num_inverted\": " << q.num_inverted << ",\n"
       << "  \"inverted\": " << JsonIntList(q.inverted) << ",\n"
       << "  \"num_degenerate\": " << q.num_degenerate << ",\n"
       << "  \"degenerate\": " << JsonIntList(q.degenerate) << ",\n"
       << "  \"num_folded\": " << num_folded << ",\n"
       << "  \"folded\": " << JsonIntList(folded) << "\n}\n";
  } else {
    os << "file:              " << options.mesh_path << "\n"
       << "format:            " << ToString(format) << "\n"
       << "vertices:          " << mesh.num_vertices() << "\n"
       << "elements:          " << mesh.num_tets() << " tetrahedra\n"
       << "surface:           " << mesh.num_surface_triangles() << " triangles, "
       << mesh.surface_vertices.size() << " vertices\n"
       << "regions:           " << per_region.size() << " (";
    bool first = true;
    for (const auto& r : per_region) {
      os << (first ? "" : ", ") << "region " << r.first << ": " << r.second;
      first = false;
    }
    os << ")\n"
       << "volume:            " << volume << "\n"
       << "bounding box:      [" << lo.x() << ", " << lo.y() << ", " << lo.z() << "] .. ["
       << hi.x() << ", " << hi.y() << ", " << hi.z() << "]  (size " << (hi - lo).x() << " x "
       << (hi - lo).y() << " x " << (hi - lo).z() << ")\n"
       << "dihedral angles:   min " << q.min_dihedral_deg << " deg, max " << q.max_dihedral_deg
       << " deg\n"
       << "aspect ratio:      max " << q.max_aspect_ratio << ", mean " << q.mean_aspect_ratio
       << "  (1 = regular)\n"
       << "inverted elements: " << q.num_inverted;
    if (!q.inverted.empty()) os << "  first: " << JsonIntList(q.inverted);
    os << "\ndegenerate:        " << q.num_degenerate;
    if (!q.degenerate.empty()) os << "  first: " << JsonIntList(q.degenerate);
    os << "\nfolded elements:   " << num_folded;
    if (num_folded > 0) os << "  first: " << JsonIntList(folded) << " (overlap a neighbour)";
    os << "\n";
  }
  std::cout << os.str();
  if (num_folded > 0) WarnFoldedElements("info", options.mesh_path, mesh);
  SetExitCode(0);
}

}  // namespace

void AddInfoCommand(CLI::App* app) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app->add_subcommand(
      "info",
      "Read a tetrahedral mesh and print its format, vertex, element and surface-triangle "
      "counts, elements per region, total volume, bounding box and element quality "
      "(dihedral angles, aspect ratios, inverted, degenerate and folded elements: readers "
      "re-orient inverted elements, so a fold in the file shows as elements overlapping a "
      "neighbour).");
  cmd->footer(
      "Formats (detected from the content, not the extension): Gmsh MSH 1/2.2/4.1 ASCII, "
      "TetGen .node/.ele (give either file or the base name), MEDIT .mesh, VTK legacy "
      "unstructured grid (ASCII or BINARY), VTU. Only tetrahedra are kept; other cells and "
      "unused vertices are dropped.\n"
      "Exit code 0 on success, 1 when the mesh cannot be read (the reason goes to stderr), 2 for a wrong or missing argument.\n"
      "Example: femreg info liver.msh --json");
  cmd->add_option("mesh", options->mesh_path, "Tetrahedral mesh file")->required();
  cmd->add_flag("--json", options->json, "Print one JSON object instead of text");
  cmd->callback([options] { RunInfo(*options); });
}

}  // namespace cli
}  // namespace femreg
