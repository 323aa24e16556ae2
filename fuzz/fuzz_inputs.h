// One input of each fuzz target through femreg's readers, shared by the libFuzzer targets
// (fuzz/*_fuzzer.cc, clang) and the regression test that replays every stored crashing
// input (tests/fuzz_regression_test.cc, the normal g++ build). Header-only so that both
// builds compile it without a library of its own.
//
// A reader is handed a file, as a user would hand it one: the input is written to a
// private temporary folder first. Every target then checks what the reader promised:
// an error names the file and stays short (tokens capped), and a mesh or cloud it accepts
// is consistent (indices in range, finite coordinates). A broken promise aborts, which
// libFuzzer reports as a crash.
#ifndef FEMREG_FUZZ_FUZZ_INPUTS_H_
#define FEMREG_FUZZ_FUZZ_INPUTS_H_

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "io/io_internal.h"
#include "registration/cloud_files.h"

namespace femreg {
namespace fuzz {

// The fuzz targets, one per format; each name is also a folder of fuzz/regressions/.
inline const std::vector<std::string>& TargetNames() {
  static const std::vector<std::string> names = {"gmsh", "tetgen", "medit", "vtk_legacy", "vtu",  "pcd",
                                                 "ply",  "xyz",    "npy",   "intrinsics", "tum",  "scene"};
  return names;
}

// Longest error message a reader may return: a few capped tokens (80 characters each)
// and a path. The 4 MB token that was once echoed whole is far beyond it.
constexpr size_t kMaxMessage = 2000;

// A folder of this process's own under the temporary directory (memory-backed /dev/shm
// when there is one: libFuzzer writes a file per execution), removed at exit.
inline char* ScratchPath() {
  static char path[4096] = "";  // a plain array: still there when atexit handlers run
  return path;
}
inline void RemoveScratchDir() {
  if (ScratchPath()[0] == '\0') return;
  std::error_code ec;
  std::filesystem::remove_all(ScratchPath(), ec);
}
inline std::string ScratchDir() {
  if (ScratchPath()[0] == '\0') {
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                  : std::filesystem::temp_directory_path();
    const std::string d = (base / ("femreg_fuzz_" + std::to_string(::getpid()))).string();
    std::snprintf(ScratchPath(), 4096, "%s", d.c_str());
    std::atexit(RemoveScratchDir);
  }
  std::error_code ec;
  std::filesystem::create_directories(ScratchPath(), ec);  // again after RemoveScratchDir
  return ScratchPath();
}

inline std::string WriteInput(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = ScratchDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

[[noreturn]] inline void Broken(const std::string& what, const std::string& detail) {
  std::fprintf(stderr, "femreg fuzz: broken promise: %s\n%.2000s\n", what.c_str(), detail.c_str());
  std::abort();
}

// An error names `path` and stays short.
inline void CheckError(const Status& status, const std::string& path) {
  if (status.ok()) return;
  if (status.message().size() > kMaxMessage) Broken("error message too long", status.message());
  if (status.message().find(path) == std::string::npos) Broken("error does not name the file", status.message());
}

inline void CheckMesh(const Status& status, const TetMesh& mesh) {
  if (!status.ok()) return;
  if (mesh.num_tets() <= 0 || mesh.num_vertices() < 4) Broken("accepted an empty mesh", "");
  if (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= mesh.num_vertices()) {
    Broken("accepted a mesh with an index out of range", "");
  }
  if (!mesh.rest.allFinite()) Broken("accepted a mesh with a non-finite vertex", "");
}

// Reads a mesh of `format` with the format's own reader (not format detection, so that
// each target stays on its format), then finishes it as ReadTetMesh does.
inline Status RunMesh(const std::string& format, const uint8_t* data, size_t size) {
  internal::RawTetMesh raw;
  Status status;
  std::string path;
  if (format == "tetgen") {
    // The .node file, a NUL byte, then the .ele file.
    size_t split = 0;
    while (split < size && data[split] != 0) ++split;
    path = WriteInput("input.node", data, split);
    WriteInput("input.ele", data + std::min(size, split + 1), size - std::min(size, split + 1));
    status = internal::ReadTetGenFiles(path, &raw);
  } else if (format == "gmsh") {
    path = WriteInput("input.msh", data, size);
    status = internal::ReadGmshFile(path, &raw);
  } else if (format == "medit") {
    path = WriteInput("input.mesh", data, size);
    status = internal::ReadMeditFile(path, &raw);
  } else if (format == "vtk_legacy") {
    path = WriteInput("input.vtk", data, size);
    status = internal::ReadVtkLegacyFile(path, &raw);
  } else {
    path = WriteInput("input.vtu", data, size);
    status = internal::ReadVtuFile(path, &raw);
  }
  CheckError(status, format == "tetgen" ? ScratchDir() + "/input." : path);
  if (!status.ok()) return status;
  TetMesh mesh;
  status = internal::FinishRawMesh(path, std::move(raw), &mesh);
  CheckError(status, format == "tetgen" ? ScratchDir() + "/input." : path);
  CheckMesh(status, mesh);
  return status;
}

inline Status RunCloud(const std::string& format, const uint8_t* data, size_t size) {
  const std::string path = WriteInput("input." + format, data, size);
  PointCloud cloud;
  SensorPose sensor;
  Status status;
  if (format == "pcd") {
    status = internal::ReadPcdFile(path, &cloud, &sensor);
  } else if (format == "ply") {
    status = internal::ReadPlyFile(path, &cloud);
  } else {
    status = ReadPointCloud(path, &cloud, nullptr, &sensor);  // text, or what it detects
  }
  CheckError(status, path);
  if (status.ok()) {
    if (cloud.points.cols() != 3) Broken("cloud points are not #P by 3", "");
    if (cloud.normals.rows() != 0 && cloud.normals.rows() != cloud.points.rows()) {
      Broken("normals do not match the points", "");
    }
    if (cloud.labels.size() != 0 && cloud.labels.size() != cloud.points.rows()) {
      Broken("labels do not match the points", "");
    }
    if (sensor.known && (!sensor.origin.allFinite() ||
                         std::abs(sensor.orientation.norm() - 1.0) > 1e-9)) {
      Broken("a sensor pose that is not finite or not a unit quaternion", "");
    }
  }
  return status;
}

// The files of depth cameras: a .npy depth image, an Open3D intrinsics JSON, a TUM list
// (in a folder that holds depth/1.png, so that a line naming it is read to the end).
inline Status RunCameraFile(const std::string& format, const uint8_t* data, size_t size) {
  Status status;
  std::string path;
  if (format == "npy") {
    path = WriteInput("input.npy", data, size);
    RawDepthImage image;
    status = ReadDepthNpy(path, &image);
    const size_t n = static_cast<size_t>(image.width) * static_cast<size_t>(image.height);
    if (status.ok() && (image.width < 1 || image.height < 1 ||
                        (image.in_metres() ? image.metres.size() : image.values.size()) != n ||
                        (image.in_metres() && !image.values.empty()))) {
      Broken("a depth image whose values do not match its size", "");
    }
  } else if (format == "intrinsics") {
    path = WriteInput("input.json", data, size);
    PinholeIntrinsics k;
    status = ReadOpen3dIntrinsics(path, &k);
    if (status.ok() && (k.width < 1 || k.height < 1 || !(k.fx > 0) || !(k.fy > 0) ||
                        !std::isfinite(k.fx) || !std::isfinite(k.fy) || !std::isfinite(k.cx) ||
                        !std::isfinite(k.cy))) {
      Broken("intrinsics that are not positive and finite", "");
    }
  } else {
    std::filesystem::create_directories(ScratchDir() + "/tum/depth");
    WriteInput("tum/depth/1.png", data, 0);
    path = WriteInput("tum/associations.txt", data, size);
    TumSequence sequence;
    status = ReadTumSequence(path, &sequence);
    if (status.ok() && sequence.frames.empty()) Broken("a TUM sequence without frames", "");
  }
  CheckError(status, path);
  return status;
}

#ifndef FEMREG_FUZZ_READERS_ONLY  // the reader targets link without the scene parser
inline Status RunScene(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Scene scene;
  const std::string source = ScratchDir() + "/scene.yaml";
  Status status = ParseScene(text, source, ScratchDir(), &scene);
  // Its messages quote a bad value by its first 80 characters and its length, as the
  // readers do (a whole document was echoed before: fuzz/regressions/scene/).
  CheckError(status, source);
  return status;
}
#else
inline Status RunScene(const uint8_t*, size_t) { std::abort(); }  // not linked in
#endif

// Runs one input through target `name` (one of TargetNames()).
inline Status RunInput(const std::string& name, const uint8_t* data, size_t size) {
  if (name == "pcd" || name == "ply" || name == "xyz") return RunCloud(name, data, size);
  if (name == "npy" || name == "intrinsics" || name == "tum") return RunCameraFile(name, data, size);
  if (name == "scene") return RunScene(data, size);
  return RunMesh(name, data, size);
}

}  // namespace fuzz
}  // namespace femreg

#endif  // FEMREG_FUZZ_FUZZ_INPUTS_H_
