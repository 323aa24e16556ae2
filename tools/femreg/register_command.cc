// femreg register: registers the scene's meshes to a sequence of point clouds.
//
// Writes, into OUT:
//   frames/<object>_NNNN.vtu   the deformed mesh per frame (displacement, residual, observed;
//                              error and error_vector with ground truth)
//   frames/cloud_NNNN.vtp      the cloud the frame was fitted to, after preprocessing
//   frames/<object>_surface_NNNN.vtp  an embedded surface (objects[i].surface) per frame
//                              (error with ground truth; .ply too with --surface-ply)
//   <object>.pvd, cloud.pvd    the ParaView collections of the sequence
//   stats.csv                  one row per frame: termination, iterations, pairs, energies,
//                              time per stage, and vertex errors when ground truth is given
//   summary.json               the run's totals, version, back end, resolved options, inputs
// The frames' files are written through a temporary file and a rename; stats.csv grows by a
// row per frame (appended and flushed); the collections and summary.json are rewritten whole
// at most once a second and when the run ends, however it ends (an error, Ctrl-C). So an
// interrupt leaves whole files behind that cover the frames done so far.
#include <algorithm>
#include <cmath>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "register_checks.h"
#include "register_outputs.h"
#include "femreg/collision.h"
#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/results.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg/version.h"
#include "mesh_warnings.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {
namespace {

using register_outputs::MakeRunInputs;
using register_outputs::RegisterArgs;
using register_outputs::ThrottledWrite;
using register_checks::CheckRegisterKeys;
using register_checks::ContactMeter;
using register_checks::WarnUnits;

int RunRegister(const RegisterArgs& args) {
  // From the start: a SIGTERM while the scene loads still ends with whole files and an
  // honest summary.
  InstallInterruptHandler();
  Scene scene;
  Status status = LoadSceneWithSets(args.scene, args.sets, &scene);
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }
  status = CheckRegisterKeys(scene);
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }
  if (!args.material.empty()) {
    Scene calibrated;
    status = LoadScene(args.material, &calibrated);
    if (status.ok()) status = CopyMaterials(calibrated, &scene);
    if (!status.ok()) {
      std::cerr << "femreg register: --material: " << status.message() << "\n";
      return 1;
    }
    for (const ObjectSpec& o : scene.objects) {
      std::cout << "Material of '" << o.name << "' from " << args.material << ": E = " << o.material.youngs_modulus
                << " Pa, nu = " << o.material.poisson_ratio << "\n";
    }
  }
  if (args.threads > 0) scene.registration.solver.num_threads = args.threads;
  const bool measure_contacts = args.no_collision && scene.effects.collision;
  if (args.no_collision) scene.effects.collision = false;
  FrameFiles frame_list;
  status = ListFrameFiles(args.frames, &frame_list);
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }
  std::vector<std::string>& files = frame_list.files;
  // --intrinsics: the camera's intrinsics from an Open3D PinholeCameraIntrinsic JSON or the
  // camera matrix as text (the image size then from the first frame), for
  // depth images; its pose stays the scene's, or, without a camera in the scene, is the
  // scene frame itself (depth images back-project into camera coordinates).
  if (!args.intrinsics.empty()) {
    if (std::none_of(files.begin(), files.end(), [](const std::string& f) { return IsDepthImageFile(f); })) {
      std::cerr << "femreg register: --intrinsics: the frames are point clouds (" << files[0]
                << "); intrinsics apply to depth images (.png, .npy)\n";
      return 1;
    }
    status = ReadCameraIntrinsics(args.intrinsics, &scene.registration.camera);
    if (!status.ok()) {
      std::cerr << "femreg register: --intrinsics: " << status.message() << "\n";
      return 1;
    }
    if (!LooksLikeJsonFile(args.intrinsics)) {
      // A camera matrix as text holds no image size: the frames' is the camera's.
      const std::string& first = *std::find_if(files.begin(), files.end(), IsDepthImageFile);
      RawDepthImage image;
      status = ReadDepthImageFile(first, &image);
      if (!status.ok()) {
        std::cerr << "femreg register: --intrinsics " << args.intrinsics
                  << " holds no image size, and the first depth frame cannot be read for it: " << status.message()
                  << "\n";
        return 1;
      }
      scene.registration.camera.width = image.width;
      scene.registration.camera.height = image.height;
    }
    scene.registration.camera.enabled = true;
  }
  // The depth scale: --depth-scale, else the layout's (TUM RGB-D: 5000 units per metre),
  // else millimetres.
  RegisterArgs resolved = args;
  if (!frame_list.tum_list.empty()) {
    if (!args.depth_scale_given) resolved.depth_scale = frame_list.depth_scale;
    resolved.tum_list = frame_list.tum_list;
    std::printf("TUM RGB-D sequence: %zu depth frames in the order of %s; depth scale %g m per unit%s\n",
                files.size(), frame_list.tum_list.c_str(), resolved.depth_scale,
                args.depth_scale_given ? " (--depth-scale)" : " (5000 per metre, TUM's)");
  }
  if (args.max_frames > 0 && static_cast<int>(files.size()) > args.max_frames) {
    files.resize(static_cast<size_t>(args.max_frames));
  }
  // Masks of depth-image frames: --mask-dir, else the scene's preprocess.mask_dir.
  if (!args.mask_dir.empty()) scene.registration.preprocess.mask_dir = args.mask_dir;
  std::string& mask_dir = scene.registration.preprocess.mask_dir;
  if (!mask_dir.empty()) {
    const char* from = args.mask_dir.empty() ? "registration.preprocess.mask_dir" : "--mask-dir";
    const auto cloud_frame = std::find_if(files.begin(), files.end(),
                                          [](const std::string& f) { return !IsDepthImageFile(f); });
    std::error_code ec;
    if (cloud_frame != files.end() && !args.mask_dir.empty()) {
      std::cerr << "femreg register: --mask-dir: masks apply to depth-image (.png, .npy) frames; "
                << *cloud_frame << " is a point cloud (crop it with registration.preprocess.crop)\n";
      return 1;
    }
    if (cloud_frame != files.end()) {
      std::fprintf(stderr, "femreg register: note: %s (%s) applies to depth-image (.png, .npy) frames; "
                   "%s is a point cloud: no masks\n", from, mask_dir.c_str(), cloud_frame->c_str());
      mask_dir.clear();
    } else if (!fs::is_directory(mask_dir, ec)) {
      std::cerr << "femreg register: " << from << ": " << mask_dir
                << ": no such folder (it holds a mask per depth frame, named like the frame)\n";
      return 1;
    }
  }
  std::vector<std::string> truth_files;
  if (!args.ground_truth.empty()) {
    status = ListFiles(args.ground_truth, {".csv"}, &truth_files);
    if (!status.ok()) {
      std::cerr << "femreg register: --ground-truth: " << status.message() << "\n";
      return 1;
    }
    // Fracture sequences keep per-piece positions and events beside the frames.
    truth_files.erase(std::remove_if(truth_files.begin(), truth_files.end(),
                                     [](const std::string& f) {
                                       const std::string n = fs::path(f).filename().string();
                                       return n == "events.csv" ||
                                              (n.size() > 11 && n.compare(n.size() - 11, 11, "_pieces.csv") == 0);
                                     }),
                      truth_files.end());
    if (truth_files.size() < files.size()) {
      std::cerr << "femreg register: --ground-truth has " << truth_files.size()
                << " frames for " << files.size() << " clouds\n";
      return 1;
    }
  }
  Scene chosen = scene;  // Tracker::Create makes the same choice
  for (const std::string& line : ChooseRegistrationElements(&chosen)) std::cout << line << "\n";
  std::unique_ptr<Tracker> tracker;
  status = Tracker::Create(scene, &tracker);
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }
  for (int i = 0; i < tracker->num_objects(); ++i) {
    WarnFoldedElements("register", "object '" + scene.objects[static_cast<size_t>(i)].name + "'",
                       tracker->mesh(i));
  }
  status = PrepareOutputDir(args.out, args.force, {"frames"},
                            {args.scene, args.frames, args.ground_truth, mask_dir, args.material, args.intrinsics});
  if (status.ok()) status = PrepareOutputDir((fs::path(args.out) / "frames").string(), true);
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }

  ContactMeter meter;
  if (measure_contacts) {
    status = meter.Init(scene, *tracker);
    if (!status.ok()) {
      std::cerr << "femreg register: " << scene.path << ": " << status.message() << "\n";
      return 1;
    }
  }
  int total_vertices = 0;
  for (int i = 0; i < tracker->num_objects(); ++i) total_vertices += tracker->mesh(i).num_vertices();
  std::cout << "femreg register: " << files.size() << " frames, " << tracker->num_objects()
            << " object(s), " << total_vertices << " vertices, regularizer "
            << ToString(scene.registration.regularizer) << ", "
            << ToString(scene.registration.solver.backend) << " back end" << std::endl;

  std::vector<FrameRecord> rows;
  std::vector<std::vector<PvdEntry>> pvd(static_cast<size_t>(tracker->num_objects()));
  std::vector<PvdEntry> cloud_pvd;
  std::vector<std::vector<PvdEntry>> surface_pvd(static_cast<size_t>(tracker->num_objects()));
  ProgressBar bar("register", static_cast<int>(files.size()), args.progress);
  bool interrupted = false;
  StatsFile stats;
  status = stats.Open((fs::path(args.out) / "stats.csv").string());
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }
  ThrottledWrite collections([&] {
    Status s = WritePvd((fs::path(args.out) / "cloud.pvd").string(), cloud_pvd);
    for (int i = 0; i < tracker->num_objects() && s.ok(); ++i) {
      s = WritePvd((fs::path(args.out) / (scene.objects[static_cast<size_t>(i)].name + ".pvd")).string(),
                   pvd[static_cast<size_t>(i)]);
      if (s.ok() && !surface_pvd[static_cast<size_t>(i)].empty()) {
        s = WritePvd((fs::path(args.out) / (scene.objects[static_cast<size_t>(i)].name + "_surface.pvd")).string(),
                     surface_pvd[static_cast<size_t>(i)]);
      }
    }
    if (s.ok()) {
      s = WriteFileAtomically((fs::path(args.out) / "summary.json").string(),
                              SummaryJson(MakeRunInputs(resolved, files, truth_files, interrupted), scene, *tracker, rows));
    }
    return s;
  });
  int start_pieces = 0;  // the objects' pieces before any frame (a break adds to them)
  {
    std::vector<int> piece;
    for (int i = 0; i < tracker->num_objects(); ++i) start_pieces += ConnectedPieces(tracker->mesh(i), &piece);
  }
  bool units_checked = false, coverage_warned = false;
  std::vector<std::string> unreadable;
  for (size_t f = 0; f < files.size(); ++f) {
    if (Interrupted()) {
      interrupted = true;
      break;
    }
    FrameRecord row;
    row.file = files[f];
    PointCloud cloud;
    int dropped = 0;
    SensorPose sensor;
    // A .png or .npy frame is a depth image, back-projected with the scene's camera.
    DepthImageOptions depth;
    depth.depth_scale = resolved.depth_scale;
    depth.mask_dir = scene.registration.preprocess.mask_dir;  // mask_dir/<frame name>.png
    Status read = ReadFrame(files[f], scene.registration.camera, depth, &cloud, &dropped, &sensor);
    if (!read.ok()) {
      if (!args.skip_bad_frames) {
        bar.Finish();
        std::cerr << "\nfemreg register: cannot read frame " << f << ": " << read.message()
                  << "\n  (the outputs cover the " << rows.size()
                  << " frames before it; --skip-bad-frames counts such frames as unusable and "
                     "goes on)\n";
        return 1;
      }
      row.read_error = read.message();
      unreadable.push_back(read.message());
      cloud = PointCloud();  // an unreadable frame is tracked as an empty one: the shape holds
    }
    // The PCL default VIEWPOINT (origin, identity) says nothing about where the sensor was.
    if (sensor.known && !(sensor.origin.isZero(0) && sensor.orientation.coeffs().isApprox(
                                                         Eigen::Quaterniond::Identity().coeffs()))) {
      cloud.has_viewpoint = true;
      cloud.viewpoint = sensor.origin;
    }
    tracker->Track(cloud, &row.summary);
    // The cloud as the tracker used it: after the mask (when read) and the scene's
    // preprocessing. The units hint looks at it, and it is written beside the meshes.
    const PointCloud& used = tracker->prepared_cloud();
    if (!units_checked && used.size() > 0) {
      units_checked = true;
      WarnUnits(files[f], used, *tracker);
    }
    if (!read.ok()) row.summary.termination = TerminationType::kInvalidInput;
    if (row.summary.pose_ambiguous) {
      bar.Finish();
      std::fprintf(stderr,
                   "femreg register: warning: frame %zu: two initial poses rotated apart explain "
                   "the cloud about equally well (a symmetric object?); the pose found may be "
                   "the other one (summary.json initial_pose)\n", f);
    }
    if (!coverage_warned && row.summary.outer_iterations > 0 && row.summary.coverage < 0.25) {
      coverage_warned = true;
      bar.Finish();
      std::fprintf(stderr,
                   "femreg register: note: frame %zu's cloud covers %.0f%% of the surface (vertices "
                   "with a cloud point within %.1f mm): a partial view; only those vertices pull "
                   "towards the cloud (visibility: %s). Shown once.\n",
                   f, 100.0 * row.summary.coverage, row.summary.trim_distance * 1e3,
                   row.summary.visibility.c_str());
    }
    if (measure_contacts) meter.Measure(*tracker, static_cast<int>(f), &row.summary);
    row.summary.nonfinite_dropped += dropped;
    row.summary.cloud_points += dropped;
    if (!read.ok()) row.summary.message = read.message() + "; " + row.summary.message;
    if (!tracker->original_vertices(0).empty()) {
      row.pieces = 0;
      std::vector<int> piece;
      for (int i = 0; i < tracker->num_objects(); ++i) row.pieces += ConnectedPieces(tracker->mesh(i), &piece);
      // The break: the first frame in more pieces than the objects started in.
      row.break_frame = rows.empty() ? -1 : rows.back().break_frame;
      if (row.break_frame < 0 && row.pieces > start_pieces) row.break_frame = static_cast<int>(f);
    }

    // Ground truth covers all objects' vertices in scene order.
    Vertices vertex_error;  // #V (all objects) by 3: result - truth, when known per vertex
    bool surface_truth = false;  // GROUND_TRUTH/surface/NAME.csv is there, for embedded surfaces
    for (int i = 0; i < tracker->num_objects() && !truth_files.empty(); ++i) {
      surface_truth = surface_truth ||
                      (tracker->has_embedded_surface(i) &&
                       fs::exists(fs::path(truth_files[f]).parent_path() / "surface" / fs::path(truth_files[f]).filename()));
    }
    if (!truth_files.empty()) {
      GroundTruthFrame truth;
      Status gt = ReadGroundTruthFrame(truth_files[f], &truth);
      int current_vertices = 0;  // fracture changes the count
      for (int i = 0; i < tracker->num_objects(); ++i) current_vertices += tracker->mesh(i).num_vertices();
      Vertices all(current_vertices, 3);
      int offset = 0;
      for (int i = 0; i < tracker->num_objects(); ++i) {
        all.middleRows(offset, tracker->vertices(i).rows()) = tracker->vertices(i);
        offset += static_cast<int>(tracker->vertices(i).rows());
      }
      const bool fracture = !tracker->original_vertices(0).empty();
      if (fracture && gt.ok()) {  // match through the original vertices, piece by piece
        std::vector<PieceTruthRow> piece_truth;
        const std::string side = (fs::path(truth_files[f]).parent_path() /
                                  (fs::path(truth_files[f]).stem().string() + "_pieces.csv")).string();
        if (fs::exists(side)) gt = ReadPieceTruth(side, &piece_truth);
        std::vector<TrackedObject> tracked;
        for (int i = 0; i < tracker->num_objects(); ++i) {
          const std::vector<int>& ids = tracker->original_vertices(i);
          tracked.push_back({&tracker->mesh(i), &tracker->vertices(i), &ids,
                             *std::max_element(ids.begin(), ids.end()) + 1});
        }
        PieceErrors pe;
        if (gt.ok()) gt = ComputePieceErrors(tracked, truth, piece_truth, &pe);
        row.piece_errors = pe.pieces;
        row.piece_seen = pe.pieces_seen;
        row.piece_hidden = pe.pieces_hidden;
        row.errors = pe.all;  // every object's vertices
        if (!gt.ok()) {
          std::cerr << "\nfemreg register: ground truth " << truth_files[f] << ": " << gt.message() << "\n";
          return 1;
        }
        row.have_errors = true;
      } else if (gt.ok() && truth.positions.rows() != total_vertices && surface_truth) {
        // The scan's ground truth serves any mesh that carries the scan: the vertices' truth is
        // another mesh's (the one the sequence was made for), and only the surface is compared.
      } else if (!gt.ok() || truth.positions.rows() != total_vertices) {
        std::cerr << "\nfemreg register: ground truth " << truth_files[f] << ": "
                  << (gt.ok() ? "has " + std::to_string(truth.positions.rows()) +
                                    " vertices, the scene " + std::to_string(total_vertices)
                              : gt.message())
                  << "\n";
        return 1;
      }
      if (!row.have_errors && gt.ok() && truth.positions.rows() == total_vertices) {
        row.errors = ComputeVertexErrors(all, truth);
        row.have_errors = true;
        vertex_error = all - truth.positions;
      }
    }

    // The embedded surfaces (objects[i].surface), all objects' in scene order, against
    // GROUND_TRUTH/surface/NAME.csv when the ground truth has them.
    int surface_rows = 0;
    for (int i = 0; i < tracker->num_objects(); ++i) surface_rows += static_cast<int>(tracker->surface_triangles(i).rows() > 0 ? tracker->surface_vertices(i).rows() : 0);
    Vertices surface_error;  // result - truth per embedded-surface vertex, when known
    if (!truth_files.empty() && surface_rows > 0) {
      const fs::path side = fs::path(truth_files[f]).parent_path() / "surface" / fs::path(truth_files[f]).filename();
      if (fs::exists(side)) {
        GroundTruthFrame truth;
        Status gt = ReadGroundTruthFrame(side.string(), &truth);
        if (gt.ok() && truth.positions.rows() != surface_rows) {
          gt = Status::Error("has " + std::to_string(truth.positions.rows()) + " rows, the embedded surfaces " +
                             std::to_string(surface_rows) + " vertices");
        }
        if (!gt.ok()) {
          std::cerr << "\nfemreg register: ground truth " << side.string() << ": " << gt.message() << "\n";
          return 1;
        }
        Vertices all(surface_rows, 3);
        int at = 0;
        for (int i = 0; i < tracker->num_objects(); ++i) {
          if (!tracker->has_embedded_surface(i)) continue;
          const Vertices v = tracker->surface_vertices(i);
          all.middleRows(at, v.rows()) = v;
          at += static_cast<int>(v.rows());
        }
        row.surface_errors = ComputeVertexErrors(all, truth);
        row.have_surface_errors = true;
        surface_error = all - truth.positions;
      }
    }

    status = register_outputs::WriteFrameFiles(args, f, scene, *tracker, used, vertex_error, surface_error,
                                               &cloud_pvd, &pvd, &surface_pvd);
    if (!status.ok()) {
      std::cerr << "\nfemreg register: " << status.message() << "\n";
      return 1;
    }
    rows.push_back(row);
    status = stats.Append(StatsRow(rows.size() - 1, rows.back()));
    if (status.ok()) status = collections.Update();
    if (!status.ok()) {
      std::cerr << "\nfemreg register: " << status.message() << "\n";
      return 1;
    }
    if (args.report == "full") {
      bar.Finish();
      std::cout << row.summary.FullReport();
    } else if (args.report == "brief" && !args.progress) {
      std::cout << row.summary.BriefReport() << "\n";
    }
    char note[128];
    std::snprintf(note, sizeof(note), "%s %.0f ms", ToString(row.summary.termination),
                  row.summary.time.total * 1e3);
    bar.Update(static_cast<int>(f + 1), note);
  }
  bar.Finish();
  if (!unreadable.empty()) {
    std::fprintf(stderr, "femreg register: %zu frame(s) could not be read and were counted as unusable "
                 "(--skip-bad-frames); the first: %s\n", unreadable.size(), unreadable[0].c_str());
  }
  if (Interrupted()) interrupted = true;
  status = collections.Flush();
  if (!status.ok()) {
    std::cerr << "femreg register: " << status.message() << "\n";
    return 1;
  }

  const RunTotals t = ComputeRunTotals(rows);
  // Both rates: the median frame's (what a camera loop sustains) and the run's (the mean,
  // which the first frame's set-up and any slow frame pull down).
  std::printf("\nRegistered %d/%zu frames (%d usable): median %.1f ms/frame (%.1f frames/s), "
              "mean %.1f ms (%.1f frames/s)\n",
              t.frames, files.size(), t.usable, t.median_ms, t.median_ms > 0 ? 1e3 / t.median_ms : 0.0,
              t.mean_ms, t.fps);
  constexpr int kTerminations = static_cast<int>(TerminationType::kStalled) + 1;
  int counts[kTerminations] = {0};
  for (const FrameRecord& r : rows) ++counts[static_cast<int>(r.summary.termination)];
  std::printf("Terminations:");
  for (int k = 0; k < kTerminations; ++k) {
    if (counts[k]) std::printf(" %s %d", ToString(static_cast<TerminationType>(k)), counts[k]);
  }
  std::printf("\n");
  if (const int stalled = counts[static_cast<int>(TerminationType::kStalled)]) {
    std::printf("  %d stalled: their solves refused most steps, each of which would invert an element or raise "
                "the energy (tiny or flat elements? docs/guide/troubleshooting.md)\n",
                stalled);
  }
  if (t.have_errors) {
    std::printf("Vertex error vs ground truth (mm): mean %.2f, max %.2f | seen: mean %.2f, max %.2f "
                "| hidden: mean %.2f, max %.2f\n",
                t.err_mean * 1e3, t.err_max * 1e3, t.seen_mean * 1e3, t.seen_max * 1e3,
                t.hidden_mean * 1e3, t.hidden_max * 1e3);
  }
  if (tracker->collision() != nullptr || measure_contacts) {
    double deepest = 0.0, sum = 0.0;
    int deepest_frame = 0;
    for (size_t f = 0; f < rows.size(); ++f) {
      sum += rows[f].summary.max_penetration;
      if (rows[f].summary.max_penetration > deepest) {
        deepest = rows[f].summary.max_penetration;
        deepest_frame = static_cast<int>(f);
      }
    }
    const double D = measure_contacts ? meter.distance() : tracker->collision()->distance();
    const double T = measure_contacts ? meter.tolerance() : tracker->collision()->tolerance();
    std::printf("Contacts%s: deepest penetration %.3f mm (frame %d), mean over frames %.3f mm; D = %.3g mm%s\n",
                measure_contacts ? " (collision off, measured only)" : "", deepest * 1e3, deepest_frame,
                rows.empty() ? 0.0 : 1e3 * sum / rows.size(), D * 1e3,
                deepest > T ? ": deeper than collision.tolerance" : "");
  }
  if (!tracker->original_vertices(0).empty()) {
    std::vector<FractureFrame> fracture(rows.size());
    for (size_t f = 0; f < rows.size(); ++f) {
      fracture[f].splits = static_cast<int>(rows[f].summary.fractures.size());
      fracture[f].pieces = rows[f].pieces;
      fracture[f].piece_errors = rows[f].piece_errors;
    }
    PrintFractureReport(fracture, args.ground_truth);
  }
  std::printf("Results in %s: %s.pvd and cloud.pvd (open in ParaView), stats.csv, summary.json\n",
              args.out.c_str(), scene.objects.empty() ? "" : scene.objects[0].name.c_str());
  if (interrupted) {
    std::fprintf(stderr, "Interrupted (%s): the files cover the %d frames done.\n", InterruptName(),
                 t.frames);
    return InterruptExitCode();
  }
  if (t.frames > 0 && t.usable == 0) {
    std::fprintf(stderr,
                 "femreg register: no frame gave a usable result (see the terminations above and "
                 "the message column of stats.csv)\n");
    return 1;
  }
  return 0;
}

}  // namespace

void AddRegisterCommand(CLI::App* app) {
  auto args = std::make_shared<RegisterArgs>();
  CLI::App* cmd = app->add_subcommand(
      "register",
      "Register the scene's tetrahedral meshes to a sequence of point clouds.\n"
      "Each frame minimizes data + elastic (corotational FEM) + temporal + anchor (+ contact) "
      "energy with Ceres or the fast back end (solver.backend).\nWrites OUT/frames/*.vtu, OUT/<object>.pvd (open in ParaView), OUT/stats.csv and "
      "OUT/summary.json.");
  cmd->add_option("--scene,-s", args->scene, "Scene file (YAML): objects, materials, registration settings")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--frames,-f", args->frames,
                  "A folder of clouds (.pcd, .ply, .xyz, .txt) or depth images (16-bit .png, .npy) in "
                  "natural order, a quoted glob pattern such as 'scans/*.pcd', or a TUM RGB-D sequence "
                  "(a folder with associations.txt or depth.txt, or such a list): its depth images in "
                  "the list's order, 5000 units per metre")
      ->required();
  cmd->add_option("--out,-o", args->out, "Output folder (refused if not empty, unless --force)")
      ->required();
  cmd->add_option("--ground-truth", args->ground_truth,
                  "Folder of per-frame ground truth CSVs (x,y,z,visible per vertex): adds vertex "
                  "errors (mm) for seen and hidden vertices; its surface/ folder (a row per vertex "
                  "of the embedded surfaces) adds their errors, and then the vertex CSVs may be "
                  "another mesh's (they are skipped)");
  cmd->add_option("--material", args->material,
                  "Take each object's material from this scene (matched by object name), e.g. "
                  "the scene.yaml `femreg calibrate` wrote: track with the identified material")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--force", args->force, "Write into a non-empty output folder (its frames/ folder, a last run's, is removed first)");
  cmd->add_flag("--surface-ply", args->surface_ply,
                "Also write each frame's embedded surfaces (objects[i].surface) as PLY beside their VTP");
  cmd->add_option("--max-frames", args->max_frames, "Register only the first N frames");
  cmd->add_option("--report", args->report, "Per-frame report: brief, full or none")
      ->check(CLI::IsMember({"brief", "full", "none"}));
  cmd->add_option("--threads", args->threads, "Solver threads (overrides the scene)");
  cmd->add_flag_callback("--no-progress", [args] { args->progress = false; }, "No progress bar (print a line per frame)");
  cmd->add_option("--depth-scale", args->depth_scale,
                  "Metres per unit of 16-bit depth frames (.png, uint16 .npy; default 0.001: "
                  "millimetres, the common sensor convention; a TUM RGB-D sequence's 0.0002); "
                  "depth frames need the scene's camera (or --intrinsics)")
      ->check(CLI::PositiveNumber)
      ->each([args](const std::string&) { args->depth_scale_given = true; });
  cmd->add_option("--intrinsics", args->intrinsics,
                  "The camera's intrinsics from an Open3D PinholeCameraIntrinsic JSON (width, height, "
                  "intrinsic_matrix), or from the 3x3 or 4x4 camera matrix as text (DeepDeform's "
                  "intrinsics.txt; width and height then the first depth frame's), replacing the scene's "
                  "fx, fy, cx, cy, width and height; the pose stays the scene's camera's (without one, the "
                  "scene frame is the camera's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--mask-dir", args->mask_dir,
                  "A folder of segmentation masks for depth frames (.png, .npy), DIR/<frame name>.png: 8- or "
                  "16-bit PNGs of the depth image's size, nonzero = the object (overrides the "
                  "scene's registration.preprocess.mask_dir); a frame without its mask is an error");
  cmd->add_flag("--skip-bad-frames", args->skip_bad_frames,
                "Count a frame that cannot be read (or whose mask is missing or of another size) "
                "as unusable and go on (default: stop with the file and the reason, exit code 1)");
  cmd->add_flag("--no-collision", args->no_collision,
                "Switch effects.collision off for this run, to compare with it on: the tracker adds "
                "no contact term, and the scene's collision section only measures the contacts and "
                "the deepest penetration of each frame's result (stats.csv)");
  AddSetOption(cmd, &args->sets);
  cmd->callback([args] { SetExitCode(RunRegister(*args)); });
}

}  // namespace cli
}  // namespace femreg
