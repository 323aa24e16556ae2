// femreg synth: ground truth sequences from a scene's synth section (a motion script
// simulated with FEM on a finer mesh, seen by a virtual depth camera).
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "mesh_warnings.h"
#include "femreg/datasets.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace femreg {
namespace cli {
namespace {

std::unique_ptr<ProgressBar> g_bar;

void Progress(int done, int total) {
  if (g_bar) g_bar->Update(done);
}

int RunSynth(const std::string& scene_path, const std::string& out, int frames, bool force,
             bool progress, double depth_scale, const std::vector<std::string>& artefacts) {
  Scene scene;
  Status status = LoadScene(scene_path, &scene);
  if (status.ok() && !scene.synth.enabled) {
    status = Status::Error(scene_path + ": has no 'synth:' section (see datasets/README.md)");
  }
  for (size_t i = 0; i < artefacts.size() && status.ok(); ++i) {
    status = SetSynthArtefact(artefacts[i], &scene.synth);
    if (!status.ok()) status = Status::Error("--artefact: " + status.message());
  }
  if (status.ok()) {
    std::string why;
    if (!scene.synth.sensor.IsValid(&why)) status = Status::Error("--artefact: " + why);
  }
  if (status.ok()) {
    std::vector<std::string> owned = {"clouds", "ground_truth", "truth"};
    if (depth_scale > 0) owned.push_back("depth");  // kept unless this run writes it (datasets/demo's)
    std::vector<std::string> inputs = {scene_path};
    for (const ObjectSpec& o : scene.objects) inputs.push_back(o.mesh_path);
    inputs.push_back(scene.synth.mesh_path);
    status = PrepareOutputDir(out, force, owned, inputs);
  }
  if (!status.ok()) {
    std::cerr << "femreg synth: " << status.message() << "\n";
    return 1;
  }
  WarnFoldedSceneMeshes("synth", scene);
  const int total = frames > 0 ? frames : scene.synth.frames;
  // A keyframe past the last frame: the motion is cut where the sequence ends.
  auto warn_past_end = [&](const std::string& what, const std::vector<MotionKeyframe>& keyframes) {
    if (!keyframes.empty() && keyframes.back().frame > scene.synth.frames - 1) {
      std::cerr << "femreg synth: warning: " << what << "'s last keyframe is at frame " << keyframes.back().frame
                << ", past the last frame (" << scene.synth.frames - 1 << ", synth.frames: " << scene.synth.frames
                << "): the motion after it is not made\n";
    }
  };
  for (size_t i = 0; i < scene.synth.motion.size(); ++i) {
    const MotionTrackSpec& track = scene.synth.motion[i];
    warn_past_end("synth.motion[" + std::to_string(i) + "]" + (track.name.empty() ? "" : " (" + track.name + ")"),
                  track.keyframes);
  }
  for (size_t i = 0; i < scene.synth.bodies.size(); ++i) {
    const SynthBodySpec& body = scene.synth.bodies[i];
    warn_past_end("synth.bodies[" + std::to_string(i) + "]" + (body.name.empty() ? "" : " (" + body.name + ")"),
                  body.keyframes);
  }
  g_bar = std::make_unique<ProgressBar>("synth", total, progress);
  SynthReport report;
  status = GenerateSynthSequence(scene, out, frames, &report, &Progress);
  g_bar->Finish();
  g_bar.reset();
  if (!status.ok()) {
    std::cerr << "femreg synth: " << status.message() << "\n";
    return 1;
  }
  if (!report.note.empty()) std::cout << "femreg synth: " << report.note << "\n";
  std::cout << "Wrote " << report.frames << " frames to " << out << ": tracked mesh "
            << report.tracked_vertices << " vertices, ground truth mesh " << report.truth_vertices
            << " vertices" << (scene.synth.sanity_check ? " (SANITY CHECK: the same mesh and material)" : "")
            << ", " << report.min_points << "-" << report.max_points << " points per cloud, "
            << static_cast<int>(100 * report.mean_seen_fraction + 0.5) << "% of the vertices seen"
            << (SynthArtefactSummary(scene.synth).empty()
                    ? ""
                    : "; artefacts: " + SynthArtefactSummary(scene.synth))
            << ".\n"
            << "Track it with: femreg register --scene " << out << "/scene.yaml --frames " << out
            << "/clouds --ground-truth " << out << "/ground_truth --out OUT\n";
  if (depth_scale > 0) {
    DepthFramesReport depth;
    status = WriteDepthFrames(out + "/clouds", scene.registration.camera, depth_scale,
                              out + "/depth", &depth);
    if (!status.ok()) {
      std::cerr << "femreg synth: --depth-png: " << status.message() << "\n";
      return 1;
    }
    std::cout << "Wrote " << depth.frames << " 16-bit depth images to " << out << "/depth ("
              << depth_scale << " m per unit; " << depth.dropped << " of " << depth.points
              << " points not in an image).\n";
  }
  return 0;
}

}  // namespace

void AddSynthCommand(CLI::App* app) {
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto frames = std::make_shared<int>(0);
  auto force = std::make_shared<bool>(false);
  auto progress = std::make_shared<bool>(true);
  auto depth_png = std::make_shared<bool>(false);
  auto depth_scale = std::make_shared<double>(0.001);
  auto artefacts = std::make_shared<std::vector<std::string>>();
  CLI::App* cmd = app->add_subcommand(
      "synth",
      "Make a synthetic sequence with ground truth from a scene's 'synth:' section: the motion "
      "script is simulated with quasi-static FEM on a ground truth mesh and rendered by a virtual "
      "depth camera. Writes OUT/scene.yaml (the tracking scene), OUT/clouds/*.pcd, "
      "OUT/ground_truth/*.csv, OUT/truth/*.vtu, OUT/forces.csv (the true external forces) and "
      "OUT/README.md. One thread, so that every run writes the same bytes.");
  cmd->add_option("scene", *scene, "Scene file with a synth section (YAML)")->required();
  cmd->add_option("--out,-o", *out, "Output folder (refused if not empty, unless --force)")->required();
  cmd->add_option("--frames", *frames,
                  "Make only the first N frames (default: synth.frames); the motion script's "
                  "timeline stays the same")
      ->check(CLI::Range(1, 100000));
  cmd->add_flag("--force", *force, "Write into a non-empty folder (the folders of frames it writes, a last run's, are removed first)");
  cmd->add_flag_callback("--no-progress", [progress] { *progress = false; }, "No progress bar");
  cmd->add_flag("--depth-png", *depth_png,
                "Also write OUT/depth/frame_NNNN.png: each cloud as the 16-bit depth image the "
                "camera stores (millimetres unless --depth-scale)");
  cmd->add_option("--depth-scale", *depth_scale, "Metres per depth unit of --depth-png")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--artefact", *artefacts,
                  "Switch on a sensor artefact over the scene's synth.artefacts (repeatable): "
                  "NAME (its realistic strength), NAME=STRENGTH, NAME.KEY=VALUE or all. Names: "
                  "flying_pixels, quantisation, dark_holes, specular_holes, grazing_holes, "
                  "multipath, flicker, flicker_dropout, occluder, leave_view "
                  "(datasets/README.md, Sensor artefacts)")
      ->take_all()
      ->allow_extra_args(false);
  cmd->callback([=] {
    SetExitCode(RunSynth(*scene, *out, *frames, *force, *progress,
                         *depth_png ? *depth_scale : 0.0, *artefacts));
  });
}

}  // namespace cli
}  // namespace femreg
