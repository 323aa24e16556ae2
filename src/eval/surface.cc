// VTU geometry in file order (femreg's own VTU reader), triangle surfaces and surface-to-surface distances.
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "femreg/eval.h"
#include "io/io_internal.h"
#include "geometry/nearest.h"

namespace femreg {
namespace {

// Collects VTK error events of one reader or writer instead of printing them.
void CollectError(vtkObject*, unsigned long, void* client_data, void* call_data) {
  auto* text = static_cast<std::string*>(client_data);
  if (call_data != nullptr && text->size() < 2000) *text += static_cast<const char*>(call_data);
}

std::vector<Eigen::Vector3d> Samples(const Vertices& points, const Triangles& triangles) {
  std::vector<Eigen::Vector3d> out;
  std::vector<char> used(static_cast<size_t>(points.rows()), 0);
  for (int f = 0; f < triangles.rows(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const int v = triangles(f, k);
      c += points.row(v).transpose() / 3.0;
      if (!used[static_cast<size_t>(v)]) {
        used[static_cast<size_t>(v)] = 1;
        out.push_back(points.row(v).transpose());
      }
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace

Triangles BoundaryFaces(const Tets& tets) {
  // The faces of tet (a, b, c, d) seen from outside, counter-clockwise.
  static const int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> count;
  for (int t = 0; t < tets.rows(); ++t) {
    for (const auto& face : kFaces) {
      std::array<int, 3> f = {tets(t, face[0]), tets(t, face[1]), tets(t, face[2])};
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto it = count.emplace(key, std::make_pair(0, f)).first;
      ++it->second.first;
    }
  }
  std::vector<std::array<int, 3>> faces;
  for (const auto& kv : count) {
    if (kv.second.first == 1) faces.push_back(kv.second.second);
  }
  Triangles out(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) out(static_cast<Eigen::Index>(i), k) = faces[i][k];
  }
  return out;
}

Status ReadVtuGeometry(const std::string& path, VtuGeometry* geometry) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Status::Error(path + ": cannot open");
  internal::VtuGrid grid;
  const Status read = internal::ReadVtuGrid(path, &grid);
  if (!read.ok()) return read;
  const internal::VtuPiece piece = internal::MergePieces(std::move(grid));
  const long long n = static_cast<long long>(piece.points.size());
  if (n == 0) return Status::Error(path + ": not a readable VTU file with points (it has none)");
  geometry->points.resize(n, 3);
  for (long long i = 0; i < n; ++i) {
    const std::array<double, 3>& point = piece.points[static_cast<size_t>(i)];
    geometry->points.row(i) << point[0], point[1], point[2];
  }
  // original_vertex, when every piece has it.
  geometry->original.clear();
  for (const internal::VtuArray& array : piece.point_data) {
    if (array.name != "original_vertex" || array.components != 1) continue;
    geometry->original.reserve(array.values.size());
    for (double v : array.values) {
      geometry->original.push_back(std::isfinite(v) && std::abs(v) < 2e9 ? static_cast<int>(std::lround(v)) : -1);
    }
    break;
  }
  geometry->rest.resize(0, 3);
  for (const internal::VtuArray& array : piece.point_data) {
    if (array.name != "displacement" || array.components != 3 ||
        array.values.size() != static_cast<size_t>(3 * n)) {
      continue;
    }
    geometry->rest = geometry->points;
    for (long long i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) geometry->rest(i, k) -= array.values[static_cast<size_t>(3 * i + k)];
    }
    break;
  }
  std::vector<std::array<int, 4>> tets;
  std::vector<std::array<int, 3>> tris;
  for (size_t c = 0; c < piece.types.size(); ++c) {
    const int type = piece.types[c];
    const long long begin = piece.offsets[c], count = piece.offsets[c + 1] - begin;
    if (!((type == VTK_TETRA && count == 4) || (type == VTK_TRIANGLE && count == 3))) continue;
    std::array<int, 4> ids{};
    for (long long k = 0; k < count; ++k) {
      const long long v = piece.connectivity[static_cast<size_t>(begin + k)];
      if (v < 0 || v >= n) {
        std::ostringstream os;
        os << path << ": cell " << c << " refers to point " << v << ", outside 0.." << n - 1;
        return Status::Error(os.str());
      }
      ids[static_cast<size_t>(k)] = static_cast<int>(v);
    }
    if (count == 4) {
      tets.push_back(ids);
    } else {
      tris.push_back({ids[0], ids[1], ids[2]});
    }
  }
  geometry->tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) geometry->tets(static_cast<Eigen::Index>(t), k) = tets[t][k];
  }
  const Triangles boundary = BoundaryFaces(geometry->tets);
  geometry->surface.resize(static_cast<Eigen::Index>(tris.size()) + boundary.rows(), 3);
  for (size_t f = 0; f < tris.size(); ++f) {
    for (int k = 0; k < 3; ++k) geometry->surface(static_cast<Eigen::Index>(f), k) = tris[f][k];
  }
  geometry->surface.bottomRows(boundary.rows()) = boundary;
  if (geometry->surface.rows() == 0) {
    return Status::Error(path + ": has neither tetrahedra nor triangles");
  }
  return Status::Ok();
}

Status WriteVtuSurface(const std::string& path, const Vertices& points, const Triangles& triangles) {
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToFloat();
  pts->SetNumberOfPoints(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) pts->SetPoint(i, points(i, 0), points(i, 1), points(i, 2));
  grid->SetPoints(pts);
  grid->Allocate(triangles.rows());
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const vtkIdType ids[3] = {triangles(f, 0), triangles(f, 1), triangles(f, 2)};
    grid->InsertNextCell(VTK_TRIANGLE, 3, ids);
  }
  const std::string temp = internal::TemporaryPathFor(path);
  std::string errors;
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(&CollectError);
  callback->SetClientData(&errors);
  internal::UseSequentialVtk();
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->AddObserver(vtkCommand::ErrorEvent, callback);
  writer->SetFileName(temp.c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  writer->SetCompressionLevel(9);
  writer->SetIdTypeToInt32();
  writer->SetHeaderTypeToUInt32();
  const int ok = writer->Write();
  if (ok != 1 || !errors.empty() || std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    return Status::Error(path + ": cannot write VTU" + (errors.empty() ? "" : ": " + errors.substr(0, 200)));
  }
  return Status::Ok();
}

SurfaceDistance ComputeSurfaceDistance(const Vertices& points_a, const Triangles& triangles_a,
                                       const Vertices& points_b, const Triangles& triangles_b) {
  SurfaceDistance d;
  if (triangles_a.rows() == 0 || triangles_b.rows() == 0) return d;
  const SurfaceIndex index_a(points_a, triangles_a, 8), index_b(points_b, triangles_b, 8);
  auto one_way = [&d](const std::vector<Eigen::Vector3d>& samples, const SurfaceIndex& other,
                      double* mean) {
    double sum = 0.0;
    for (const Eigen::Vector3d& p : samples) {
      const double dist = std::sqrt(other.Closest(p).squared_distance);
      sum += dist;
      d.hausdorff = std::max(d.hausdorff, dist);
    }
    *mean = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
  };
  const std::vector<Eigen::Vector3d> sa = Samples(points_a, triangles_a);
  const std::vector<Eigen::Vector3d> sb = Samples(points_b, triangles_b);
  d.samples_a = static_cast<int>(sa.size());
  d.samples_b = static_cast<int>(sb.size());
  one_way(sa, index_b, &d.a_to_b_mean);
  one_way(sb, index_a, &d.b_to_a_mean);
  d.mean = 0.5 * (d.a_to_b_mean + d.b_to_a_mean);
  return d;
}

}  // namespace femreg
