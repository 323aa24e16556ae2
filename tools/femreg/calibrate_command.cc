// femreg calibrate --scene SCENE --observed CLOUD... --out DIR: fits a material parameter
// (Young's modulus by default) of a scene object so that its simulated equilibrium under
// the scene's loads and boundary conditions matches the observed clouds
// (femreg/calibration.h). Writes DIR/calibration.json, DIR/scene.yaml (the scene with the
// fitted value) and DIR/misfit.png.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "femreg/calibration.h"
#include "femreg/forward_results.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"

namespace femreg {
namespace cli {
namespace {

namespace fs = std::filesystem;

struct CalibrateArgs {
  std::string scene_path;
  std::vector<std::string> observed;
  std::string out_dir;
  std::string object;
  // The search's options, with their defaults, where the flags write them (femreg/calibration.h);
  // --param and --object are parsed into it.
  CalibrationOptions options;
  std::string param = ToString(CalibrationOptions{}.parameter);
  bool no_preprocess = false;
  bool plot = true;
  bool force = false;
};

void Fail(const std::string& message) {
  std::cerr << "femreg calibrate: " << message << "\n";
  SetExitCode(1);
}

// The plotting script beside the sources, or installed.
std::string FindMisfitScript() {
  const std::vector<fs::path> candidates = {
      fs::path(FEMREG_SOURCE_DIR) / "tools" / "plot_misfit.py",
      fs::read_symlink("/proc/self/exe").parent_path() / ".." / "share" / "femreg" / "plot_misfit.py"};
  std::error_code ec;
  for (const auto& c : candidates) {
    if (fs::exists(c, ec)) return c.string();
  }
  return "";
}

void RunCalibrate(const CalibrateArgs& args) {
  Scene scene;
  Status status = LoadScene(args.scene_path, &scene);
  if (!status.ok()) return Fail(status.message());

  CalibrationOptions options = args.options;
  if (!FromString(args.param, &options.parameter)) {
    return Fail("--param " + args.param + ": use E, nu or region_E");
  }
  options.object = -1;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (args.object.empty() ? i == 0 : scene.objects[i].name == args.object) {
      options.object = static_cast<int>(i);
      break;
    }
  }
  if (options.object < 0) return Fail("--object " + args.object + ": the scene has no such object");
  if (args.object.empty() && scene.objects.size() > 1) {
    return Fail("the scene has " + std::to_string(scene.objects.size()) +
                " objects: say which one with --object");
  }
  std::string error;
  if (!options.IsValid(&error)) {
    // The message names the option's field; say which flag sets it.
    const std::pair<const char*, const char*> flags[] = {
        {"region", "--region"},   {"lower", "--lower"},         {"upper", "--upper"},
        {"grid_samples", "--grid"}, {"tolerance", "--tolerance"}, {"max_evaluations", "--max-evaluations"},
        {"loss_scale", "--loss-scale"}, {"max_distance", "--max-distance"}};
    for (const auto& [field, flag] : flags) {
      if (error.rfind(field, 0) == 0) return Fail(std::string(flag) + ": " + error);
    }
    return Fail(error);
  }

  std::vector<PointCloud> clouds;
  std::vector<int> points;
  for (const std::string& path : args.observed) {
    PointCloud cloud;
    int dropped = 0;
    SensorPose pose;
    status = ReadPointCloud(path, &cloud, &dropped, &pose);
    if (!status.ok()) return Fail(status.message());
    if (!args.no_preprocess) {
      const Eigen::Vector3d viewpoint =
          pose.known ? pose.origin : scene.registration.camera.position;
      PreprocessPointCloud(scene.registration.preprocess, &cloud, nullptr, viewpoint);
    }
    if (cloud.size() == 0) return Fail(path + ": no point left (after the scene's preprocess)");
    points.push_back(cloud.size());
    clouds.push_back(std::move(cloud));
  }

  const Status prepared = PrepareOutputDir(args.out_dir, args.force);
  if (!prepared.ok()) return Fail("--out " + prepared.message());
  const fs::path out(args.out_dir);

  std::cout << "calibrating " << ToString(options.parameter) << " of "
            << scene.objects[options.object].name << " against " << clouds.size()
            << " cloud(s)\n";
  Scene chosen = scene;  // Calibrate makes the same choice; the written scene keeps the file's
  for (const std::string& line : ChooseForwardElements(&chosen)) std::cout << line << "\n";
  CalibrationSummary summary;
  status = Calibrate(scene, clouds, options, &summary, args.observed);
  if (!status.ok()) return Fail(status.message());
  std::cout << summary.BriefReport() << "\n";

  const std::string json_path = (out / "calibration.json").string();
  status = WriteFileAtomically(json_path, CalibrationJson({args.scene_path, args.observed, points}, scene, options, summary));
  if (!status.ok()) return Fail(status.message());
  std::cout << "wrote " << json_path << "\n";

  if (summary.IsSolutionUsable()) {
    const Scene fitted = ApplyCalibration(scene, options, summary.value);
    std::ostringstream comment;
    comment << args.scene_path << " with " << ToString(options.parameter) << " fitted by femreg "
            << "calibrate to " << summary.num_points << " observed points: "
            << summary.value << " (was " << summary.initial_value << "), mean distance "
            << summary.mean_distance * 1e3 << " mm";
    const std::string scene_out = (out / "scene.yaml").string();
    status = WriteScene(fitted, scene_out, comment.str());
    if (!status.ok()) return Fail(status.message());
    std::cout << "wrote " << scene_out << "\n";
  }

  if (args.plot && !summary.samples.empty()) {
    const std::string script = FindMisfitScript();
    const std::string png = (out / "misfit.png").string();
    const std::string python = FindPython();
    if (script.empty() || python.empty() || RunProgram({python, script, json_path, png}) != 0) {
      std::cerr << "femreg calibrate: no plot drawn (needs tools/plot_misfit.py and matplotlib; "
                   "set FEMREG_PYTHON to a python that has it)\n";
    } else {
      std::cout << "wrote " << png << "\n";
    }
  }
  if (!summary.IsSolutionUsable()) Fail(summary.message);
}

}  // namespace

void AddCalibrateCommand(CLI::App* app) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app->add_subcommand(
      "calibrate",
      "Fit a material parameter (Young's modulus by default) so that the scene's simulated "
      "equilibrium matches observed point clouds.");
  cmd->footer(
      "Every observed cloud is a view of the object in equilibrium under the scene's\n"
      "boundary conditions, loads and gravity (the scene's frame, metres); the scene's\n"
      "registration.preprocess (crop, plane removal, ...) is applied to it. The misfit of a\n"
      "value is the mean robust (Huber, capped at --max-distance) distance of the points to\n"
      "the simulated surface; a grid over the interval (log-spaced for E) brackets the best\n"
      "value, ranking by the same misfit with a log tail beyond --max-distance instead of the\n"
      "cap (informative far from the fit), and a golden-section search refines it.\n"
      "Writes DIR/calibration.json (value, misfit, uncertainty, every sample), DIR/scene.yaml\n"
      "(the scene with the fitted value: pass it to femreg register --scene) and\n"
      "DIR/misfit.png. Exit code 1 when the fit is not usable: no load (the parameter cannot\n"
      "be observed), a cloud that does not overlap the object, a best value at an end of the\n"
      "interval (widen it), a forward solve that does not converge.\n"
      "Example: femreg calibrate --scene datasets/sag_track/calibration.yaml\n"
      "           --observed datasets/sag_track/clouds/frame_0000.pcd --out /tmp/cal");
  cmd->add_option("--scene,-s", args->scene_path, "Scene file (YAML)")->required();
  cmd->add_option("--observed", args->observed, "Observed cloud(s): PCD, PLY or text")
      ->required()
      ->expected(1, -1);
  cmd->add_option("--out,-o", args->out_dir, "Output folder (created when missing)")->required();
  cmd->add_option("--object", args->object, "The object to fit (required with several)");
  cmd->add_option("--param", args->param, "E (default), nu, or region_E (with --region)")
      ->check(CLI::IsMember({"E", "nu", "region_E"}));
  cmd->add_option("--region", args->options.region, "Region id for --param region_E");
  cmd->add_option("--lower", args->options.lower,
                  "Lower end of the search interval (default: scene's E / 10; nu: 0)");
  cmd->add_option("--upper", args->options.upper,
                  "Upper end of the search interval (default: scene's E * 10; nu: 0.495)");
  cmd->add_option("--grid", args->options.grid_samples, "Samples of the bracketing grid (>= 3)")
      ->capture_default_str();
  cmd->add_option("--tolerance", args->options.tolerance,
                  "Golden section stops at this bracket width (in ln E, or in nu)")
      ->capture_default_str();
  cmd->add_option("--max-evaluations", args->options.max_evaluations, "Forward solves in all")
      ->capture_default_str();
  cmd->add_option("--loss-scale", args->options.loss_scale, "Huber scale of the distance (m)")
      ->capture_default_str();
  cmd->add_option("--max-distance", args->options.max_distance,
                  "Points farther than this from the simulated surface count as outliers (m)")
      ->capture_default_str();
  cmd->add_flag("--no-preprocess", args->no_preprocess,
                "Use the clouds as read (skip the scene's registration.preprocess)");
  cmd->add_flag("!--no-plot", args->plot, "Do not draw misfit.png");
  cmd->add_flag("-v,--verbose", args->options.verbose, "One line per forward solve");
  cmd->add_flag("-f,--force", args->force, "Write into a non-empty output folder");
  cmd->callback([args] { RunCalibrate(*args); });
}

}  // namespace cli
}  // namespace femreg
