// Format detection, ReadTetMesh and the checks shared by all readers.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <sys/stat.h>

#include "femreg/io.h"
#include "io/io_internal.h"
#include "io/text_tokens.h"

namespace femreg {
namespace internal {

Status FileError(const std::string& path, int line, const std::string& message) {
  std::ostringstream os;
  os << path;
  if (line > 0) os << ":" << line;
  os << ": " << message;
  return Status::Error(os.str());
}

std::string ExactNumber(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

Status ReadSmallFile(const std::string& path, std::streamoff max_bytes, const std::string& what,
                     std::string* text) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return FileError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  const std::streamoff size = in.tellg();
  if (size > max_bytes) return FileError(path, 0, std::to_string(size) + " bytes: too large for " + what);
  in.seekg(0);
  text->assign(static_cast<size_t>(std::max<std::streamoff>(size, 0)), '\0');
  in.read(&(*text)[0], size);
  if (!in) return FileError(path, 0, "cannot read");
  return Status::Ok();
}

bool RegionIdFrom(double value, int* id) {
  const double rounded = std::round(value);
  if (!std::isfinite(rounded) || rounded < static_cast<double>(std::numeric_limits<int>::min()) ||
      rounded > static_cast<double>(std::numeric_limits<int>::max())) {
    return false;
  }
  *id = static_cast<int>(rounded);
  return true;
}

bool LooksLikeRegionName(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* key : {"region", "tag", "material", "physical", "domain", "label",
                          "subdomain", "cellentityids", "entity"}) {
    if (lower.find(key) != std::string::npos) return true;
  }
  return false;
}

Status FinishRawMesh(const std::string& path, RawTetMesh raw, TetMesh* mesh) {
  const int nv = static_cast<int>(raw.vertices.size());
  const int nt = static_cast<int>(raw.tets.size());
  const bool have_lines = raw.tet_lines.size() == raw.tets.size();
  auto where = [&](int t) {
    std::ostringstream os;
    if (!have_lines) os << "element " << t << ": ";
    return os.str();
  };
  auto line_of = [&](int t) { return have_lines ? raw.tet_lines[t] : 0; };
  const std::string element_file = raw.lines_file.empty() ? path : raw.lines_file;
  if (nt == 0) return FileError(path, 0, "no tetrahedra (is this a surface mesh?)");
  if (!raw.regions.empty() && raw.regions.size() != raw.tets.size()) {
    return FileError(path, 0, "region ids do not match the number of tetrahedra");
  }

  // Indices, then drop vertices that no tet uses.
  std::vector<int> new_index(nv, -1);
  int used = 0;
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      const int v = raw.tets[t][k];
      if (v < 0 || v >= nv) {
        std::ostringstream os;
        os << where(t) << "tetrahedron refers to vertex index " << v << ", outside 0.." << nv - 1;
        return FileError(element_file, line_of(t), os.str());
      }
      new_index[v] = 0;  // used; numbered below in the original order
    }
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        if (raw.tets[t][a] == raw.tets[t][b]) {
          return FileError(element_file, line_of(t),
                           where(t) + "degenerate tetrahedron: a vertex appears twice");
        }
      }
    }
  }
  for (int v = 0; v < nv; ++v) {
    if (new_index[v] >= 0) new_index[v] = used++;
  }
  TetMesh out;
  out.rest.resize(used, 3);
  for (int v = 0; v < nv; ++v) {
    if (new_index[v] < 0) continue;
    for (int k = 0; k < 3; ++k) out.rest(new_index[v], k) = raw.vertices[v][k];
    if (!out.rest.row(new_index[v]).allFinite()) {
      std::ostringstream os;
      os << "vertex " << v << " has a non-finite coordinate";
      return FileError(path, 0, os.str());
    }
  }
  out.tets.resize(nt, 4);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) out.tets(t, k) = new_index[raw.tets[t][k]];
  }
  out.region = Eigen::VectorXi::Zero(nt);
  for (int t = 0; t < static_cast<int>(raw.regions.size()); ++t) out.region(t) = raw.regions[t];

  // Degenerate elements, with the criterion of FinalizeMesh but naming the line.
  double edge_sum = 0.0;
  for (int t = 0; t < nt; ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        edge_sum += (out.rest.row(out.tets(t, i)) - out.rest.row(out.tets(t, j))).norm();
      }
    }
  }
  const double h = edge_sum / (6.0 * nt);
  const double kTolerance = 1e-12;
  for (int t = 0; t < nt; ++t) {
    const double vol =
        SignedTetVolume(out.rest.row(out.tets(t, 0)), out.rest.row(out.tets(t, 1)),
                        out.rest.row(out.tets(t, 2)), out.rest.row(out.tets(t, 3)));
    if (std::abs(vol) <= kTolerance * h * h * h) {
      std::ostringstream os;
      os << where(t) << "degenerate tetrahedron (zero volume: " << vol << ")";
      return FileError(element_file, line_of(t), os.str());
    }
  }
  Status status = FinalizeMesh(&out, path, kTolerance);
  if (!status.ok()) return status;
  *mesh = std::move(out);
  return Status::Ok();
}

}  // namespace internal

const char* ToString(MeshFormat format) {
  switch (format) {
    case MeshFormat::kGmsh: return "gmsh";
    case MeshFormat::kTetGen: return "tetgen";
    case MeshFormat::kMedit: return "medit";
    case MeshFormat::kVtkLegacy: return "vtk-legacy";
    case MeshFormat::kVtu: return "vtu";
    case MeshFormat::kUnknown: break;
  }
  return "unknown";
}

namespace {

bool FileExists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The first `n` bytes of a file ("" when it cannot be read).
std::string Head(const std::string& path, size_t n) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::string data(n, '\0');
  in.read(&data[0], static_cast<std::streamsize>(n));
  data.resize(static_cast<size_t>(in.gcount()));
  return data;
}

// The first line that is neither blank nor a '#' comment.
std::string FirstContentLine(const std::string& head) {
  std::istringstream in(head);
  std::string line;
  while (std::getline(in, line)) {
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    return line.substr(start);
  }
  return "";
}

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// A TetGen header: 3 or 4 integers ("#points dim #attributes #markers" or
// "#tets nodes-per-tet #attributes").
bool LooksLikeTetGenHeader(const std::string& line) {
  std::istringstream in(line);
  std::string word;
  int count = 0;
  while (in >> word) {
    if (word[0] == '#') break;
    long long v;
    if (!internal::ParseInt(word, &v)) return false;
    ++count;
  }
  return count == 3 || count == 4;
}

std::string TetGenBase(const std::string& path) {
  if (EndsWith(path, ".node")) return path.substr(0, path.size() - 5);
  if (EndsWith(path, ".ele")) return path.substr(0, path.size() - 4);
  return path;
}

std::string SurfaceFormatName(const std::string& path, const std::string& head) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (StartsWith(head, "ply")) return "PLY";
  if (StartsWith(FirstContentLine(head), "solid") || EndsWith(lower, ".stl")) return "STL";
  if (EndsWith(lower, ".obj") || StartsWith(FirstContentLine(head), "v ") ||
      StartsWith(FirstContentLine(head), "mtllib") || StartsWith(FirstContentLine(head), "o "))
    return "OBJ";
  if (EndsWith(lower, ".off") || StartsWith(head, "OFF")) return "OFF";
  return "";
}

}  // namespace

MeshFormat DetectMeshFormat(const std::string& path) {
  if (!FileExists(path)) {
    if (FileExists(path + ".node") && FileExists(path + ".ele")) return MeshFormat::kTetGen;
    return MeshFormat::kUnknown;
  }
  const std::string head = Head(path, 4096);
  const size_t start = head.find_first_not_of(" \t\r\n");
  const std::string body = start == std::string::npos ? "" : head.substr(start);
  if (StartsWith(body, "<")) {
    if (body.find("<VTKFile") != std::string::npos &&
        body.find("UnstructuredGrid") != std::string::npos)
      return MeshFormat::kVtu;
    return MeshFormat::kUnknown;
  }
  if (StartsWith(body, "# vtk DataFile") || StartsWith(body, "# vtk datafile"))
    return MeshFormat::kVtkLegacy;
  if (StartsWith(body, "$MeshFormat") || StartsWith(body, "$NOD") || StartsWith(body, "$Nodes") ||
      StartsWith(body, "$Comments") || StartsWith(body, "$PhysicalNames"))
    return MeshFormat::kGmsh;
  const std::string first = FirstContentLine(head);
  if (StartsWith(first, "MeshVersionFormatted")) return MeshFormat::kMedit;
  if (LooksLikeTetGenHeader(first)) {
    const std::string base = TetGenBase(path);
    if (FileExists(base + ".node") && FileExists(base + ".ele")) return MeshFormat::kTetGen;
  }
  return MeshFormat::kUnknown;
}

namespace {

Status ReadTetMeshUnchecked(const std::string& path, TetMesh* mesh) {
  internal::RawTetMesh raw;
  Status status;
  const MeshFormat format = DetectMeshFormat(path);
  switch (format) {
    case MeshFormat::kGmsh: status = internal::ReadGmshFile(path, &raw); break;
    case MeshFormat::kTetGen: status = internal::ReadTetGenFiles(path, &raw); break;
    case MeshFormat::kMedit: status = internal::ReadMeditFile(path, &raw); break;
    case MeshFormat::kVtkLegacy: status = internal::ReadVtkLegacyFile(path, &raw); break;
    case MeshFormat::kVtu: status = internal::ReadVtuFile(path, &raw); break;
    case MeshFormat::kUnknown: {
      if (!FileExists(path) && !FileExists(TetGenBase(path) + ".node")) {
        return Status::Error(path + ": no such file");
      }
      const std::string surface = SurfaceFormatName(path, Head(path, 4096));
      if (!surface.empty()) {
        return Status::Error(path + ": no tetrahedra: this is a surface mesh (" + surface +
                             "), not a volume mesh; femreg needs a tetrahedral mesh "
                             "(Gmsh, TetGen, MEDIT, VTK or VTU): tetrahedralize it first, "
                             "e.g. `femreg mesh SURFACE --out MESH.vtu --edge-length L`");
      }
      return Status::Error(path +
                           ": unsupported or unrecognized mesh format (expected Gmsh .msh, "
                           "TetGen .node/.ele, MEDIT .mesh, VTK legacy or VTU)");
    }
  }
  if (!status.ok()) return status;
  return internal::FinishRawMesh(path, std::move(raw), mesh);
}

}  // namespace

Status ReadTetMesh(const std::string& path, TetMesh* mesh) {
  // The readers check every count against the file's length before they size anything;
  // this is the last line for a file that is valid but larger than memory.
  try {
    return ReadTetMeshUnchecked(path, mesh);
  } catch (const std::bad_alloc&) {
    return Status::Error(path + ": out of memory while reading the mesh");
  } catch (const std::length_error& e) {
    return Status::Error(path + ": out of memory while reading the mesh (" + e.what() + ")");
  }
}

}  // namespace femreg
