// femreg/camera_io.h - the files of depth cameras and of the tools around them: depth images
// (16-bit PNG, NumPy .npy), segmentation masks (PNG), pinhole intrinsics (Open3D's
// PinholeCameraIntrinsic JSON, or the matrix as text) and recordings in the TUM RGB-D layout. Files only: the
// camera model and the back-projection are the registration module's (femreg/point_cloud.h).
#ifndef FEMREG_CAMERA_IO_H_
#define FEMREG_CAMERA_IO_H_

#include <cstdint>
#include <string>
#include <vector>

#include "femreg/status.h"

namespace femreg {

// A depth image as stored, row-major, one of two kinds:
//  - `values`: integer depth units (a 16-bit PNG, a uint16 .npy), 0 = no return; metres are
//    units * DepthImageOptions::depth_scale;
//  - `metres`: depths in metres (a float .npy, an Open3D RGBDImage); 0, a negative or a
//    non-finite value = no return. depth_scale does not apply.
// Exactly one of them holds width * height values.
struct RawDepthImage {
  int width = 0, height = 0;
  std::vector<uint16_t> values;
  std::vector<float> metres;
  bool in_metres() const { return !metres.empty(); }
};

// ---- PNG (depth_png.cc, libpng)

// Reads a 16-bit single-channel (greyscale) PNG. Other bit depths or colour types are
// refused naming the file and what it holds; so are images over 2^28 pixels.
Status ReadDepthPng(const std::string& path, RawDepthImage* image);
// Reads a mask of width by height pixels (any PNG, 8- or 16-bit, grey or colour; non-zero
// in any colour channel = keep). Errors name the file (and both sizes when they differ).
Status ReadMaskPng(const std::string& path, int width, int height, std::vector<uint8_t>* keep);
// Writes a 16-bit greyscale PNG, atomically (a temporary file renamed into place). An
// image in metres is refused (a PNG holds integer units).
Status WriteDepthPng(const std::string& path, const RawDepthImage& image);
// Writes width * height keep flags as an 8-bit greyscale PNG (255 keep, 0 drop), atomically.
Status WriteMaskPng(const std::string& path, int width, int height, const std::vector<uint8_t>& keep);

// ---- NumPy .npy (npy_reader.cc)

// Reads an (H, W) array saved by numpy.save (format versions 1, 2 and 3): float32 or
// float64 depths in metres ('<f4', '<f8': `metres`), or uint16 depth units ('<u2':
// `values`); either byte order, C or Fortran order (fortran_order: True is transposed into
// rows). The header is parsed as the Python dict it is (the keys descr, fortran_order and
// shape, in any order); other dtypes, ranks, a data size that does not match the shape or
// images over 2^28 pixels are refused. Errors name the file and the header field or the
// byte offset.
Status ReadDepthNpy(const std::string& path, RawDepthImage* image);

// ---- Either, by extension (depth_image_file.cc)

// Reads a depth image by its file's extension (any case): .npy with ReadDepthNpy, .png with
// ReadDepthPng. Another extension is refused naming the file.
Status ReadDepthImageFile(const std::string& path, RawDepthImage* image);

// ---- Open3D's PinholeCameraIntrinsic JSON (open3d_intrinsics.cc)

// Pinhole intrinsics in pixels: pixel centres at integer coordinates, x right, y down (the
// convention of Open3D, OpenCV and femreg's CameraOptions).
struct PinholeIntrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

// Reads {"width": W, "height": H, "intrinsic_matrix": [9 numbers]}, as
// open3d.io.write_pinhole_camera_intrinsic writes it: the 3x3 matrix column-major, so
// [fx, 0, 0, 0, fy, 0, cx, cy, 1]. Width and height must be positive integers, fx and fy
// positive, the skew and the other zeros zero and the corner 1 (a row-major matrix is
// refused with that hint). Other keys are ignored. Errors name the file and the field
// ("camera.json: intrinsic_matrix[4] (fy): must be > 0 (got 0)") or the line and column of a
// JSON syntax error.
Status ReadOpen3dIntrinsics(const std::string& path, PinholeIntrinsics* intrinsics);
// Writes the same layout (what Open3D reads back), atomically.
Status WriteOpen3dIntrinsics(const std::string& path, const PinholeIntrinsics& intrinsics);

// ---- A pinhole matrix as text (matrix_intrinsics.cc)

// Reads the camera matrix as numpy.savetxt writes it (and numpy.loadtxt reads it): rows of
// whitespace-separated numbers, row-major, either the 3x3 K = [fx 0 cx; 0 fy cy; 0 0 1] or
// K padded to a 4x4 homogeneous matrix (DeepDeform's intrinsics.txt). '#' starts a comment.
// The zeros and the 1s of K (and of the padding) must be there, fx and fy positive. The
// file holds no image size: width and height are returned 0. Errors name the file, the
// line and the entry ("intrinsics.txt:2: [1][1] (fy): must be > 0 (got 0)").
Status ReadMatrixIntrinsics(const std::string& path, PinholeIntrinsics* intrinsics);
// True when the file's first character that is not white space is '{' (a JSON object: an
// Open3D file), false for anything else (a matrix, or a file that cannot be read).
bool LooksLikeJsonFile(const std::string& path);

// ---- The TUM RGB-D layout (tum_sequence.cc)

// A TUM RGB-D sequence stores depth as 16-bit PNGs of 5000 units per metre.
constexpr double kTumDepthScale = 1.0 / 5000.0;  // metres per unit

// One line of a TUM list.
struct TumFrame {
  double time = 0;         // the depth image's timestamp (s)
  std::string depth;       // the depth image, resolved against the list's folder
  double rgb_time = 0;     // from an associations line; 0 and "" from depth.txt
  std::string rgb;
  int line = 0;            // 1-based line of the list
};

struct TumSequence {
  std::string list;             // the list read (associations.txt, depth.txt, or the file given)
  std::vector<TumFrame> frames;  // in the list's order
};

// The TUM list of folder `dir`: the first of associations.txt, association.txt,
// associate.txt and depth.txt there that looks like one (LooksLikeTumList); "" when none.
std::string FindTumList(const std::string& dir);
// True when the first line of `path` that is neither blank nor a '#' comment is
// "timestamp path" or "timestamp path timestamp path" with a path ending in .png or .npy:
// a TUM list, not a text point cloud (whose lines are numbers).
bool LooksLikeTumList(const std::string& path);

// Reads a TUM list: `path` is the list file or a folder holding one (FindTumList). Lines:
// "timestamp depth_path" (depth.txt) or "timestamp path timestamp path" (an associations
// file, as TUM's associate.py writes it: the depth image is the path under depth/, else the
// second one); '#' starts a comment, blank lines are skipped. Paths are relative to the
// list's folder. Every depth image must exist. Errors name the list and the line
// ("associations.txt:7: depth/1305031102.160407.png: no such file").
Status ReadTumSequence(const std::string& path, TumSequence* sequence);

}  // namespace femreg

#endif  // FEMREG_CAMERA_IO_H_
