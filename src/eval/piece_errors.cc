// Ground truth for meshes that split: the per-piece side file and the piece matching.
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "femreg/eval.h"
#include "femreg/io.h"

namespace femreg {

Status ReadPieceTruth(const std::string& path, std::vector<PieceTruthRow>* rows) {
  rows->clear();
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || line.rfind("vertex,piece,x,y,z", 0) != 0) {
    return Status::Error(path + ":1: expected the header vertex,piece,x,y,z");
  }
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    PieceTruthRow r;
    if (std::sscanf(line.c_str(), "%d,%d,%lf,%lf,%lf", &r.vertex, &r.piece, &r.position.x(),
                    &r.position.y(), &r.position.z()) != 5 ||
        r.vertex < 0 || !r.position.allFinite()) {
      return Status::Error(path + ":" + std::to_string(number) + ": expected vertex,piece,x,y,z");
    }
    rows->push_back(r);
  }
  return Status::Ok();
}

Status WritePieceTruth(const std::string& path, const std::vector<PieceTruthRow>& rows) {
  std::ostringstream os;
  os << "vertex,piece,x,y,z\n";
  char buf[160];
  for (const PieceTruthRow& r : rows) {
    std::snprintf(buf, sizeof(buf), "%d,%d,%.9g,%.9g,%.9g\n", r.vertex, r.piece, r.position.x(),
                  r.position.y(), r.position.z());
    os << buf;
  }
  return WriteFileAtomically(path, os.str());
}

namespace {

// Where a tracked vertex v lies on truth piece `on` when the truth has no row for it there: a
// tracked mesh that splits on its own nodes, not on the truth's crack, can leave a copy of a
// split vertex on a piece whose material does not reach it. It is compared with the rigid motion
// of the nearest vertices of its tracked piece that have a row on that piece (the best fit of
// their rest to their true positions; the 12 nearest, ties included), not with another piece's
// position; `fallback` when fewer than 4 have one.
Eigen::Vector3d Extrapolated(const TetMesh& mesh, const std::vector<int>& original, const std::vector<int>& piece,
                             const std::map<int, std::map<int, Eigen::Vector3d>>& sided, int v, int on,
                             const Eigen::Vector3d& fallback) {
  constexpr size_t kNeighbours = 12;
  const Eigen::Vector3d X = mesh.rest.row(v).transpose();
  std::vector<std::pair<double, int>> near;
  for (int u = 0; u < mesh.num_vertices(); ++u) {
    if (piece[u] != piece[v]) continue;
    auto it = sided.find(original[u]);
    if (it == sided.end() || !it->second.count(on)) continue;
    near.emplace_back((mesh.rest.row(u).transpose() - X).squaredNorm(), u);
  }
  if (near.size() < 4) return fallback;
  // The 12 nearest and every vertex as near as the 12th: on a regular mesh many are equally
  // near, and rest positions read back from a file must pick the same set.
  std::sort(near.begin(), near.end());
  size_t n = std::min(kNeighbours, near.size());
  const double reach = near[n - 1].first * (1.0 + 1e-6) + 1e-18;
  while (n < near.size() && near[n].first <= reach) ++n;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> a(n), b(n);
  for (size_t k = 0; k < n; ++k) {
    const int u = near[k].second;
    a[k] = mesh.rest.row(u).transpose();
    b[k] = sided.at(original[u]).at(on);
    ca += a[k] / static_cast<double>(n);
    cb += b[k] / static_cast<double>(n);
  }
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < n; ++k) H += (a[k] - ca) * (b[k] - cb).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
  return R * (X - ca) + cb;
}

}  // namespace

PieceErrors ComputePieceErrors(const TetMesh& mesh, const Vertices& positions,
                               const std::vector<int>& original, const GroundTruthFrame& truth,
                               const std::vector<PieceTruthRow>& piece_truth) {
  PieceErrors out;
  std::vector<int> piece;
  const int num_pieces = ConnectedPieces(mesh, &piece);
  // Original vertex -> (truth piece -> position).
  std::map<int, std::map<int, Eigen::Vector3d>> sided;
  for (const PieceTruthRow& r : piece_truth) sided[r.vertex][r.piece] = r.position;
  // Match each tracked piece to the truth piece most of its unambiguous vertices are on.
  std::vector<std::map<int, int>> votes(num_pieces);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    auto it = sided.find(original[v]);
    if (it != sided.end() && it->second.size() == 1) ++votes[piece[v]][it->second.begin()->first];
  }
  std::vector<int> match(num_pieces, -1);
  for (int p = 0; p < num_pieces; ++p) {
    int best = 0;
    for (const auto& kv : votes[p]) {
      if (kv.second > best) {
        best = kv.second;
        match[p] = kv.first;
      }
    }
  }
  // Tracked copies per original vertex: only a vertex the tracker split can be on a piece
  // its truth is not on (an intact tracked body beside a broken truth keeps its rows).
  std::vector<int> copies(truth.positions.rows() > 0 ? static_cast<size_t>(truth.positions.rows()) : 0, 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (original[v] >= static_cast<int>(copies.size())) copies.resize(static_cast<size_t>(original[v]) + 1, 0);
    ++copies[static_cast<size_t>(original[v])];
  }
  Vertices truth_positions(mesh.num_vertices(), 3);
  GroundTruthFrame matched;
  matched.visible.resize(mesh.num_vertices());
  std::vector<std::vector<double>> per_piece(num_pieces), seen(num_pieces), hidden(num_pieces);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const int o = original[v];
    Eigen::Vector3d p = truth.positions.row(o).transpose();
    auto it = sided.find(o);
    if (it != sided.end()) {
      auto jt = it->second.find(match[piece[v]]);
      if (jt != it->second.end()) {
        p = jt->second;
      } else if (match[piece[v]] >= 0 && copies[static_cast<size_t>(o)] > 1) {
        p = Extrapolated(mesh, original, piece, sided, v, match[piece[v]], p);
      }
    }
    truth_positions.row(v) = p.transpose();
    matched.visible[v] = o < static_cast<int>(truth.visible.size()) ? truth.visible[o] : 0;
    const double error = (positions.row(v).transpose() - p).norm();
    per_piece[piece[v]].push_back(error);
    (matched.visible[v] ? seen : hidden)[piece[v]].push_back(error);
  }
  matched.positions = truth_positions;
  out.all = ComputeVertexErrors(positions, matched);
  out.matched = std::move(matched);
  for (int p = 0; p < num_pieces; ++p) {
    out.piece_vertices.push_back(static_cast<int>(per_piece[p].size()));
    out.pieces.push_back(ComputeErrorStats(per_piece[p]));
    out.pieces_seen.push_back(ComputeErrorStats(seen[p]));
    out.pieces_hidden.push_back(ComputeErrorStats(hidden[p]));
  }
  return out;
}

Status ComputePieceErrors(const std::vector<TrackedObject>& objects, const GroundTruthFrame& truth,
                          const std::vector<PieceTruthRow>& piece_truth, PieceErrors* out) {
  *out = PieceErrors();
  Eigen::Index total = 0;
  for (const TrackedObject& o : objects) total += o.positions->rows();
  Vertices positions(total, 3);
  out->matched.positions.resize(total, 3);
  int first = 0;
  Eigen::Index row = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    const TrackedObject& o = objects[i];
    if (first + o.initial > truth.positions.rows() ||
        static_cast<size_t>(first + o.initial) > truth.visible.size()) {
      return Status::Error("has " + std::to_string(truth.positions.rows()) +
                           " vertices, fewer than the objects had at the start");
    }
    GroundTruthFrame object_truth;
    object_truth.positions = truth.positions.middleRows(first, o.initial);
    object_truth.visible.assign(truth.visible.begin() + first, truth.visible.begin() + first + o.initial);
    std::vector<PieceTruthRow> object_pieces;
    for (PieceTruthRow r : piece_truth) {
      if (r.vertex >= first && r.vertex < first + o.initial) {
        r.vertex -= first;
        object_pieces.push_back(r);
      }
    }
    const PieceErrors pe = ComputePieceErrors(*o.mesh, *o.positions, *o.original, object_truth, object_pieces);
    out->pieces.insert(out->pieces.end(), pe.pieces.begin(), pe.pieces.end());
    out->pieces_seen.insert(out->pieces_seen.end(), pe.pieces_seen.begin(), pe.pieces_seen.end());
    out->pieces_hidden.insert(out->pieces_hidden.end(), pe.pieces_hidden.begin(), pe.pieces_hidden.end());
    out->piece_vertices.insert(out->piece_vertices.end(), pe.piece_vertices.begin(), pe.piece_vertices.end());
    const Eigen::Index n = o.positions->rows();
    positions.middleRows(row, n) = *o.positions;
    out->matched.positions.middleRows(row, n) = pe.matched.positions;
    out->matched.visible.insert(out->matched.visible.end(), pe.matched.visible.begin(), pe.matched.visible.end());
    row += n;
    first += o.initial;
  }
  out->all = ComputeVertexErrors(positions, out->matched);
  return Status::Ok();
}

}  // namespace femreg
