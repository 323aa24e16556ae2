// The bundled fracture sequences' generator (datasets/beam_break, datasets/slab_tear,
// datasets/beam_cut; their settings: fracture_scenarios.cc): ground truth from the forward
// simulator with fracture on a mesh twice as fine as the tracked one (detection and splits
// between quasi-static solves, SolveQuasiStaticWithFracture), seen by the virtual depth
// camera. Deterministic.
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <cstdio>
#include <filesystem>
#include <map>
#include <ostream>
#include <sstream>

#include "datasets/fracture_scenarios.h"
#include "femreg/datasets.h"
#include "femreg/eval.h"
#include "femreg/forward.h"
#include "femreg/fracture.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace fs = std::filesystem;

namespace femreg {

namespace {

using fracture_scenarios::Scenario;
using fracture_scenarios::TrackingScene;

// Removes the elements of `mesh` for which drop(e) is true and the vertices left without
// one; `original` follows the kept vertices. The model is rebuilt on the new mesh.
void RemoveElements(const std::function<bool(int)>& drop, const Material& material,
                    TetMesh* mesh, ElasticModel* model, std::vector<int>* original) {
  std::vector<int> kept_tets;
  std::vector<int> index(mesh->num_vertices(), -1);
  for (int e = 0; e < mesh->num_tets(); ++e) {
    if (drop(e)) continue;
    kept_tets.push_back(e);
    for (int k = 0; k < 4; ++k) index[mesh->tets(e, k)] = 0;
  }
  std::vector<int> kept_vertices;
  for (int v = 0; v < mesh->num_vertices(); ++v) {
    if (index[v] < 0) continue;
    index[v] = static_cast<int>(kept_vertices.size());
    kept_vertices.push_back(v);
  }
  TetMesh out;
  out.rest = RemapRows(mesh->rest, kept_vertices);
  out.x = RemapRows(mesh->x, kept_vertices);
  out.tets.resize(static_cast<Eigen::Index>(kept_tets.size()), 4);
  out.region.resize(static_cast<Eigen::Index>(kept_tets.size()));
  for (size_t i = 0; i < kept_tets.size(); ++i) {
    for (int k = 0; k < 4; ++k) out.tets(static_cast<Eigen::Index>(i), k) = index[mesh->tets(kept_tets[i], k)];
    out.region(static_cast<Eigen::Index>(i)) = mesh->region(kept_tets[i]);
  }
  BuildTopology(&out);
  ComputeLumpedMasses(&out, material.density);
  std::vector<int> carried(kept_vertices.size());
  if (original->empty()) {
    carried = kept_vertices;
  } else {
    for (size_t v = 0; v < kept_vertices.size(); ++v) carried[v] = (*original)[kept_vertices[v]];
  }
  *original = std::move(carried);
  *mesh = std::move(out);
  model->Build(*mesh, ElasticModelType::kCorotational, material);
}

Status FindScenario(const std::string& scenario, Scenario* s) {
  if (scenario == "beam_break") {
    *s = fracture_scenarios::BeamBreak();
  } else if (scenario == "slab_tear") {
    *s = fracture_scenarios::SlabTear();
  } else if (scenario == "beam_cut") {
    *s = fracture_scenarios::BeamCut();
  } else {
    return Status::Error("unknown scenario '" + scenario + "' (beam_break, slab_tear or beam_cut)");
  }
  return Status::Ok();
}

// The ground truth's mesh, before any break.
TetMesh FineMesh(const Scenario& s, int refinement) {
  const Eigen::Vector3i fine_cells = s.fine_cells.x() > 0 ? s.fine_cells : Eigen::Vector3i(s.cells * refinement);
  return MakeBox(s.size, fine_cells.x(), fine_cells.y(), fine_cells.z());
}

// Whether element e of the fine mesh is in the cut's slab (by its rest centroid).
bool InSlab(const Scenario& s, const TetMesh& fine, int e) {
  double cx = 0;
  for (int k = 0; k < 4; ++k) cx += 0.25 * fine.rest(fine.tets(e, k), 0);
  return cx > s.cut_lo && cx < s.cut_hi;
}

// The grippers' displacements at frame f, of the fine vertices they hold (by rest position):
// vertex, displacement from rest.
std::vector<std::pair<int, Eigen::Vector3d>> GripperDisplacements(const Scenario& s, const TetMesh& fine, int f) {
  Eigen::Matrix3d Rl, Rr;
  Eigen::Vector3d tl, tr;
  s.left(f, &Rl, &tl);
  s.right(f, &Rr, &tr);
  Eigen::Vector3d cl = Eigen::Vector3d::Zero(), cr = Eigen::Vector3d::Zero();
  int nl = 0, nr = 0;
  for (int v = 0; v < fine.num_vertices(); ++v) {
    if (fine.rest(v, 0) <= s.left_x) { cl += fine.rest.row(v).transpose(); ++nl; }
    if (fine.rest(v, 0) >= s.right_x) { cr += fine.rest.row(v).transpose(); ++nr; }
  }
  cl /= std::max(nl, 1);
  cr /= std::max(nr, 1);
  std::vector<std::pair<int, Eigen::Vector3d>> out;
  for (int v = 0; v < fine.num_vertices(); ++v) {
    const Eigen::Vector3d X = fine.rest.row(v);
    if (X.x() <= s.left_x) out.emplace_back(v, cl + Rl * (X - cl) + tl - X);
    if (X.x() >= s.right_x) out.emplace_back(v, cr + Rr * (X - cr) + tr - X);
  }
  return out;
}

Status Generate(const std::string& scenario, const std::string& dir, const std::vector<Vertices>* truth,
                const std::string& truth_source, void (*progress)(int done, int total)) {
  Scenario s;
  Status found = FindScenario(scenario, &s);
  if (!found.ok()) return found;
  if (truth) {
    if (s.cut_frame < 0) return Status::Error(scenario + ": a given ground truth is for a cut scenario only");
    s.name += "_calculix";
    s.title += ", the ground truth by CalculiX";
  }
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "clouds", ec);
  fs::create_directories(fs::path(dir) / "ground_truth", ec);
  if (ec) return Status::Error(dir + ": cannot create: " + ec.message());

  const int refinement = 2;
  TetMesh coarse = MakeBox(s.size, s.cells.x(), s.cells.y(), s.cells.z());
  const Eigen::Vector3i fine_cells = s.fine_cells.x() > 0 ? s.fine_cells : Eigen::Vector3i(s.cells * refinement);
  TetMesh fine = FineMesh(s, refinement);
  if (truth) {
    if (static_cast<int>(truth->size()) != s.frames) {
      return Status::Error("the ground truth has " + std::to_string(truth->size()) + " frames, " + s.name + " " +
                           std::to_string(s.frames));
    }
    for (const Vertices& u : *truth) {
      if (u.rows() != fine.num_vertices()) {
        return Status::Error("a ground truth frame has " + std::to_string(u.rows()) + " vertices, the mesh " +
                             std::to_string(fine.num_vertices()));
      }
    }
  }
  const double mid = 0.5 * s.size.x();
  for (int e = 0; e < fine.num_tets(); ++e) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * fine.rest(fine.tets(e, k), 0);
    if (s.cut_frame < 0 && std::abs(cx - mid) < s.weak_half_width) fine.region(e) = 1;
  }
  ComputeLumpedMasses(&fine, s.material.density);
  ElasticModel model;
  model.Build(fine, ElasticModelType::kCorotational, s.material);
  const TetMesh fine0 = fine;  // the unbroken mesh, for the embedding
  const EmbeddedPoints embedded = EmbedPoints(fine0, coarse.rest);
  // Every initial fine element that contains each tracked vertex (for the pieces file).
  std::vector<std::vector<std::pair<int, Eigen::Vector4d>>> containing(coarse.num_vertices());
  for (int e = 0; e < fine0.num_tets(); ++e) {
    Eigen::Matrix3d D;
    const Eigen::Vector3d a = fine0.rest.row(fine0.tets(e, 0));
    for (int k = 0; k < 3; ++k) D.col(k) = fine0.rest.row(fine0.tets(e, k + 1)).transpose() - a;
    const Eigen::Matrix3d Dinv = D.inverse();
    Eigen::Vector3d lo = a, hi = a;
    for (int k = 1; k < 4; ++k) {
      lo = lo.cwiseMin(fine0.rest.row(fine0.tets(e, k)).transpose());
      hi = hi.cwiseMax(fine0.rest.row(fine0.tets(e, k)).transpose());
    }
    for (int v = 0; v < coarse.num_vertices(); ++v) {
      const Eigen::Vector3d p = coarse.rest.row(v);
      if ((p.array() < lo.array() - 1e-9).any() || (p.array() > hi.array() + 1e-9).any()) continue;
      const Eigen::Vector3d l = Dinv * (p - a);
      const Eigen::Vector4d b(1 - l.sum(), l.x(), l.y(), l.z());
      if (b.minCoeff() >= -1e-9) containing[v].emplace_back(e, b);
    }
  }

  FractureOptions fracture;
  fracture.toughness = s.cut_frame >= 0 ? 0.0 : s.toughness;  // a cut: nothing breaks by itself
  if (s.cut_frame < 0) fracture.region_toughness = {{1, s.weak_toughness}};
  fracture.max_splits_per_iteration = 16;
  fracture.max_splits_per_frame = 400;
  ForwardOptions forward;
  forward.num_threads = 1;  // one summation order: the same bytes on every machine load
  forward.max_iterations = 60;
  DepthSensorOptions sensor_options;
  sensor_options.camera = s.camera;
  sensor_options.pixel_stride = s.pixel_stride;
  const DepthSensor sensor(sensor_options);

  const std::string made_by = truth ? "`tools/make_calculix_cut.sh`: CalculiX's solution of `femreg fracture-data "
                                      "--scenario " + scenario + " --calculix-deck`, then `femreg fracture-data "
                                      "--scenario " + scenario + " --calculix-result`"
                                    : "`femreg fracture-data --scenario " + s.name + "`";
  Status status = WriteScene(TrackingScene(s), (fs::path(dir) / "scene.yaml").string(),
                             s.title + ": " + s.description + ".\nMade by " + made_by + " (see README.md).");
  if (!status.ok()) return status;
  std::vector<int> original;  // fine vertex -> initial fine vertex
  if (truth) {  // (the solve starts it otherwise)
    original.resize(static_cast<size_t>(fine.num_vertices()));
    for (int v = 0; v < fine.num_vertices(); ++v) original[static_cast<size_t>(v)] = v;
  }
  std::vector<FractureEvent> events;
  std::ostringstream events_csv;
  events_csv << "frame,node,nx,ny,nz,measure,pieces\n";
  int first_break = -1, first_event = -1;
  for (int f = 0; f < s.frames; ++f) {
    // Boundary conditions on the current (possibly split) mesh, by rest position.
    ForwardProblem problem;
    problem.prescribed = GripperDisplacements(s, fine, f);
    if (f == s.cut_frame) {
      RemoveElements(
          [&](int e) {
            double cx = 0;
            for (int k = 0; k < 4; ++k) cx += 0.25 * fine.rest(fine.tets(e, k), 0);
            return cx > s.cut_lo && cx < s.cut_hi;
          },
          s.material, &fine, &model, &original);
      first_event = f;
      // The cut as one event (node -1: no node split; the plane's normal, no measure).
      events_csv << f << ",-1,1,0,0,0,2\n";
      // The conditions again, on the cut mesh's vertices.
      problem = ForwardProblem();
      problem.prescribed = GripperDisplacements(s, fine, f);
    }
    ForwardSummary summary;
    const size_t before = events.size();
    if (truth) {  // given: the initial vertex each current one comes from moved by it
      fine.x.resize(fine.num_vertices(), 3);
      for (int v = 0; v < fine.num_vertices(); ++v) {
        const int v0 = original[static_cast<size_t>(v)];
        fine.x.row(v) = fine.rest.row(v) + (*truth)[static_cast<size_t>(f)].row(v0);
      }
    } else {
      status = SolveQuasiStaticWithFracture(&problem, forward, fracture, 12, s.material.density,
                                            &model, &fine, &original, &events, &summary);
    }
    if (!status.ok()) return Status::Error(s.name + " frame " + std::to_string(f) + ": " + status.message());
    std::vector<int> fine_piece;
    const int pieces = ConnectedPieces(fine, &fine_piece);
    for (size_t i = before; i < events.size(); ++i) {
      const FractureEvent& e = events[i];
      char buf[200];
      std::snprintf(buf, sizeof(buf), "%d,%d,%.6f,%.6f,%.6f,%.6g,%d\n", f, e.original_node,
                    e.normal.x(), e.normal.y(), e.normal.z(), e.measure, pieces);
      events_csv << buf;
      if (first_event < 0) first_event = f;
    }
    if (pieces >= 2 && first_break < 0) first_break = f;

    // Ground truth at the tracked vertices: initial element -> its current copy.
    std::map<std::array<int, 4>, int> element_of;
    for (int e = 0; e < fine.num_tets(); ++e) {
      std::array<int, 4> key;
      for (int k = 0; k < 4; ++k) key[k] = original[fine.tets(e, k)];
      std::sort(key.begin(), key.end());
      element_of[key] = e;
    }
    auto current = [&](int e0) {
      std::array<int, 4> key;
      for (int k = 0; k < 4; ++k) key[k] = fine0.tets(e0, k);
      std::sort(key.begin(), key.end());
      auto it = element_of.find(key);
      return it == element_of.end() ? -1 : it->second;
    };
    // The current element with the same vertices, in the initial element's vertex order.
    auto interpolate = [&](int e0, int e, const Eigen::Vector4d& b) {
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        int vertex = -1;
        for (int m = 0; m < 4; ++m) {
          if (original[fine.tets(e, m)] == fine0.tets(e0, k)) vertex = fine.tets(e, m);
        }
        p += b[k] * fine.x.row(vertex).transpose();
      }
      return p;
    };
    GroundTruthFrame truth;
    truth.positions.resize(coarse.num_vertices(), 3);
    std::vector<PieceTruthRow> piece_rows;
    for (int v = 0; v < coarse.num_vertices(); ++v) {
      int e0 = embedded.element[v];
      Eigen::Vector4d b = embedded.barycentric[v];
      int e = current(e0);
      if (e < 0) {  // removed by the fracture: any other element containing the vertex
        for (const auto& c : containing[v]) {
          if ((e = current(c.first)) >= 0) {
            e0 = c.first;
            b = c.second;
            break;
          }
        }
      }
      truth.positions.row(v) = e >= 0 ? Eigen::RowVector3d(interpolate(e0, e, b).transpose())
                                      : Eigen::RowVector3d(coarse.rest.row(v));
      if (pieces >= 2) {
        std::map<int, Eigen::Vector3d> on_piece;
        for (const auto& c : containing[v]) {
          const int ce = current(c.first);
          if (ce < 0) continue;
          const int p = fine_piece[fine.tets(ce, 0)];
          if (!on_piece.count(p)) on_piece[p] = interpolate(c.first, ce, c.second);
        }
        if (s.cut_frame >= 0) {
          // Near a cut, a vertex that a tracked mesh splits on its nodes (not on the cut) may
          // end up on the piece it is not in: there it moves with that piece's nearest element
          // (the affine map of its rest to its current shape, extrapolated), within one tracked
          // cell of the piece.
          const double reach = s.size.x() / s.cells.x();
          const Eigen::Vector3d X = coarse.rest.row(v);
          std::map<int, std::pair<double, int>> nearest;  // piece -> (distance, element)
          for (int e = 0; e < fine.num_tets(); ++e) {
            const int p = fine_piece[fine.tets(e, 0)];
            if (on_piece.count(p)) continue;
            Eigen::Vector3d c = Eigen::Vector3d::Zero();
            for (int k = 0; k < 4; ++k) c += 0.25 * fine.rest.row(fine.tets(e, k)).transpose();
            const double d = (c - X).norm();
            auto it = nearest.find(p);
            if (it == nearest.end() || d < it->second.first) nearest[p] = {d, e};
          }
          for (const auto& kv : nearest) {
            if (kv.second.first > reach) continue;
            const int e = kv.second.second;
            Eigen::Matrix3d D, Dx;
            const Eigen::Vector3d a = fine.rest.row(fine.tets(e, 0)), ax = fine.x.row(fine.tets(e, 0));
            for (int k = 0; k < 3; ++k) {
              D.col(k) = fine.rest.row(fine.tets(e, k + 1)).transpose() - a;
              Dx.col(k) = fine.x.row(fine.tets(e, k + 1)).transpose() - ax;
            }
            on_piece[kv.first] = ax + Dx * (D.inverse() * (X - a));
          }
        }
        for (const auto& kv : on_piece) piece_rows.push_back({v, kv.first, kv.second});
      }
    }
    const std::vector<RenderSurface> surfaces = {{&fine.x, &fine.surface}};
    const DepthImage image = sensor.Render(surfaces);
    const PointCloud cloud = sensor.Sample(image, surfaces, 1000003ull + static_cast<uint64_t>(f));
    truth.visible = sensor.Visible(image, truth.positions, 2e-3);
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    status = WritePointCloud((fs::path(dir) / "clouds" / (std::string(name) + ".pcd")).string(), cloud);
    if (status.ok()) {
      status = WriteGroundTruthFrame(
          (fs::path(dir) / "ground_truth" / (std::string(name) + ".csv")).string(), truth);
    }
    if (status.ok() && pieces >= 2) {
      status = WritePieceTruth(
          (fs::path(dir) / "ground_truth" / (std::string(name) + "_pieces.csv")).string(), piece_rows);
    }
    if (!status.ok()) return status;
    if (progress) progress(f + 1, s.frames);
  }
  status = WriteFileAtomically((fs::path(dir) / "ground_truth" / "events.csv").string(), events_csv.str());
  if (!status.ok()) return status;

  std::ostringstream truth_text;
  if (truth) {
    truth_text << "The ground truth is " << truth_source << " on a " << fine_cells.x() << " x " << fine_cells.y()
               << " x " << fine_cells.z() << " box mesh (" << fine0.num_vertices() << " nodes, " << fine0.num_tets()
               << " C3D4, faces at x = " << s.cut_lo << " and " << s.cut_hi << " m): `*ELASTIC` under NLGEOM, one "
               << "static step per frame with the grippers' displacements; in frame " << s.cut_frame
               << "'s step its elements between the faces are removed (`*MODEL CHANGE, TYPE=ELEMENT, REMOVE`): "
               << "the beam is in two pieces from frame " << first_break << ". A tracked "
               << "vertex within one tracked cell of a piece it is not in also has a row on that piece: "
               << "the piece's nearest element's motion, extrapolated to it (a tracked mesh that "
               << "splits on its own nodes puts it there).\n";
  } else if (s.cut_frame >= 0) {
    truth_text << "The ground truth is a corotational FEM simulation (quasi-static, one solve per "
               << "frame) on a " << fine_cells.x() << " x " << fine_cells.y() << " x " << fine_cells.z()
               << " box mesh (" << fine0.num_vertices() << " vertices, faces at x = " << s.cut_lo
               << " and " << s.cut_hi << " m). At frame " << s.cut_frame << " its elements between them "
               << "are removed: the beam is in two pieces from frame " << first_break << ". A tracked "
               << "vertex within one tracked cell of a piece it is not in also has a row on that piece: "
               << "the piece's nearest element's motion, extrapolated to it (a tracked mesh that "
               << "splits on its own nodes puts it there).\n";
  } else {
    truth_text << "The ground truth is a corotational FEM simulation on a mesh " << refinement
               << " times finer (" << fine0.num_vertices() << " vertices) with the fracture model: "
               << "per frame a quasi-static solve, then detection and up to "
               << fracture.max_splits_per_iteration << " splits, repeated (at most 12 rounds) until "
               << "no node breaks. Its middle band (|x - " << mid << "| < " << s.weak_half_width
               << " m) has toughness " << s.weak_toughness << " Pa, the rest does not break. "
               << "First split at frame " << first_event << ", in two pieces from frame "
               << first_break << " (" << events.size() << " splits in all).\n";
  }
  std::ostringstream readme;
  readme << "# " << s.name << ": " << s.title << "\n\n"
         << (truth ? "Made by " + made_by + " (deterministic for one CalculiX version).\n\n"
                   : "Made by `femreg fracture-data --scenario " + s.name + " --out DIR` (deterministic).\n\n")
         << "The object is " << s.description << ".\n\n"
         << "- `scene.yaml`: the tracking scene: a " << s.size.x() << " x " << s.size.y() << " x "
         << s.size.z() << " m box (E = " << s.material.youngs_modulus << " Pa, nu = "
         << s.material.poisson_ratio << "), " << coarse.num_vertices() << " vertices, "
         << coarse.num_tets() << " tetrahedra, toughness " << s.tracked_toughness
         << " Pa, `effects.fracture` on"
         << (s.tracked_max_cracks == 0 ? std::string()
             : s.tracked_data_gap
                 ? " (one crack, placed where the data shows the slab open: `max_cracks: " +
                       std::to_string(s.tracked_max_cracks) + ", data_gap: true`)"
                 : s.cut_through
                 ? " (one crack, cut through the section once it opens: `max_cracks: " +
                       std::to_string(s.tracked_max_cracks) + ", cut_through: true`)"
                 : " (one crack that grows from its front: `max_cracks: " +
                       std::to_string(s.tracked_max_cracks) + "`)")
         << (s.tracked_visibility ? std::string()
                                  : std::string(", `registration.data.auto_visibility: false` (every surface vertex "
                                                "pulled to its nearest point: the silhouette's ends pin the "
                                                "sliding along the beam that point-to-plane leaves free)"))
         << "; the grippers the robot knows as hard anchors.\n"
         << "- `clouds/frame_NNNN.pcd`: " << s.frames << " clouds from a virtual "
         << s.camera.width << "x" << s.camera.height << " depth camera (every " << s.pixel_stride
         << "nd pixel, depth noise sigma = 0.00285 z^2).\n"
         << "- `ground_truth/frame_NNNN.csv`: per tracked vertex of the initial mesh (x,y,z,visible).\n"
         << "- `ground_truth/frame_NNNN_pieces.csv` (frames after the break): the position of "
         << "each tracked vertex on every ground-truth piece it touches (vertex,piece,x,y,z); "
         << "`femreg register --ground-truth` matches each tracked piece to a ground-truth "
         << "piece with it (femreg/eval.h, ComputePieceErrors).\n"
         << "- `ground_truth/events.csv`: the ground truth's node splits (frame, node, plane "
         << "normal, measure, pieces).\n\n"
         << truth_text.str();
  return WriteFileAtomically((fs::path(dir) / "README.md").string(), readme.str());
}

}  // namespace

std::vector<std::string> FractureScenarios() { return {"beam_break", "slab_tear", "beam_cut"}; }

Status GenerateFractureSequence(const std::string& scenario, const std::string& dir,
                                void (*progress)(int done, int total)) {
  return Generate(scenario, dir, nullptr, "", progress);
}

Status GenerateFractureSequence(const std::string& scenario, const std::string& dir,
                                const std::vector<Vertices>& truth, const std::string& truth_source,
                                void (*progress)(int done, int total)) {
  return Generate(scenario, dir, &truth, truth_source, progress);
}

Status WriteFractureSequenceDeck(const std::string& scenario, std::ostream& out) {
  Scenario s;
  Status found = FindScenario(scenario, &s);
  if (!found.ok()) return found;
  if (s.cut_frame < 0) {
    return Status::Error(scenario + ": a CalculiX deck is written for a cut scenario only (the others break "
                         "by femreg's fracture model)");
  }
  const TetMesh fine = FineMesh(s, 2);
  auto write_set = [&out](const std::string& kind, const std::string& name, const std::vector<int>& ids) {
    out << "*" << kind << ", " << kind << "=" << name << "\n";
    for (size_t i = 0; i < ids.size(); ++i) out << ids[i] + 1 << (i % 10 == 9 || i + 1 == ids.size() ? "\n" : ", ");
  };
  out.precision(15);
  out << "** femreg fracture-data --scenario " << scenario << " --calculix-deck: " << fine.num_vertices()
      << " nodes, " << fine.num_tets() << " C3D4, one step per frame (" << s.frames << ")\n*NODE, NSET=Nall\n";
  for (int v = 0; v < fine.num_vertices(); ++v) {
    out << v + 1 << ", " << fine.rest(v, 0) << ", " << fine.rest(v, 1) << ", " << fine.rest(v, 2) << "\n";
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=Eall\n";
  std::vector<int> slab;
  for (int e = 0; e < fine.num_tets(); ++e) {
    out << e + 1;
    for (int k = 0; k < 4; ++k) out << ", " << fine.tets(e, k) + 1;
    out << "\n";
    if (InSlab(s, fine, e)) slab.push_back(e);
  }
  write_set("ELSET", "Eslab", slab);
  out << "*MATERIAL, NAME=M\n*ELASTIC\n" << s.material.youngs_modulus << ", " << s.material.poisson_ratio
      << "\n*SOLID SECTION, ELSET=Eall, MATERIAL=M\n";
  for (int f = 0; f < s.frames; ++f) {
    out << "** frame " << f << "\n*STEP, NLGEOM, INC=1000\n";
    if (f == s.cut_frame) out << "*MODEL CHANGE, TYPE=ELEMENT, REMOVE\nEslab\n";
    // Each step ends at the total time f + 1 (the frame's displacements: the last block there).
    out << "*STATIC\n0.25, 1.0, 1e-6, 0.25\n*BOUNDARY\n";
    // ccx reads at most 20 characters a number: 12 digits, and round-off below a femtometre as 0.
    out.precision(12);
    for (const auto& [v, u] : GripperDisplacements(s, fine, f)) {
      for (int a = 0; a < 3; ++a) {
        out << v + 1 << ", " << a + 1 << ", " << a + 1 << ", " << (std::abs(u(a)) < 1e-15 ? 0.0 : u(a)) << "\n";
      }
    }
    out.precision(15);
    out << "*NODE PRINT, NSET=Nall\nU\n*END STEP\n";
  }
  return out ? Status::Ok() : Status::Error("cannot write the deck");
}

}  // namespace femreg
