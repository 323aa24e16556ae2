// Python bindings: the files of depth cameras (femreg/camera_io.h) - NumPy depth frames,
// intrinsics (Open3D's JSON or the matrix as text, or a PinholeCameraIntrinsic object), TUM RGB-D
// sequences - and the frames of a recording as `femreg register` lists and reads them.
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "femreg/camera_io.h"
#include "femreg/point_cloud.h"

namespace femreg {
namespace python {
namespace {

// `camera`'s pose (or the default camera's) with these intrinsics.
CameraOptions WithIntrinsics(const py::object& camera, const PinholeIntrinsics& k) {
  CameraOptions c = camera.is_none() ? CameraOptions() : camera.cast<CameraOptions>();
  SetIntrinsics(k, &c);
  return c;
}

}  // namespace

void BindCameraFiles(py::module_& m) {
  m.def("read_depth_npy",
        [](const std::string& path) -> py::array {
          RawDepthImage image;
          Check(ReadDepthNpy(path, &image));
          const std::vector<py::ssize_t> shape = {image.height, image.width};
          if (image.in_metres()) {
            py::array_t<float> out(shape);
            std::memcpy(out.mutable_data(), image.metres.data(), image.metres.size() * sizeof(float));
            return std::move(out);
          }
          py::array_t<uint16_t> out(shape);
          std::memcpy(out.mutable_data(), image.values.data(), image.values.size() * sizeof(uint16_t));
          return std::move(out);
        },
        py::arg("path"),
        "A depth image saved by numpy.save, checked: (H, W) float32 metres (from '<f4' or "
        "'<f8') or uint16 depth units ('<u2'), C or Fortran order. femreg.Error names the file "
        "and the header field otherwise.");

  m.def("read_intrinsics",
        [](const std::string& path, const py::object& camera) {
          CameraOptions c = camera.is_none() ? CameraOptions() : camera.cast<CameraOptions>();
          Check(ReadCameraIntrinsics(path, &c));
          if (camera.is_none() && !LooksLikeJsonFile(path)) {
            Check(Status::Error(path + ": a camera matrix holds no image size: pass camera= "
                                "with the depth images' width and height"));
          }
          return c;
        },
        py::arg("path"), py::arg("camera") = py::none(),
        "A CameraOptions with the intrinsics of a file and the pose of `camera` (default: the "
        "camera frame is the scene frame): fx, fy, cx, cy, width and height from an Open3D "
        "PinholeCameraIntrinsic JSON file; fx, fy, cx and cy from the camera matrix as text "
        "(3x3, or 4x4 as DeepDeform's intrinsics.txt), whose width and height stay `camera`'s (required then). "
        "femreg.Error names the file and the field.");
  m.def("write_intrinsics",
        [](const std::string& path, const CameraOptions& c) { Check(WriteCameraIntrinsics(path, c)); },
        py::arg("path"), py::arg("camera"),
        "Writes the camera's intrinsics as Open3D's PinholeCameraIntrinsic JSON "
        "(open3d.io.read_pinhole_camera_intrinsic reads it); atomic.");
  m.def("camera_from_open3d",
        [](const py::object& intrinsic, const py::object& camera) {
          if (!IsOpen3d(intrinsic, "PinholeCameraIntrinsic")) {
            throw py::type_error("camera_from_open3d: expected an open3d.camera.PinholeCameraIntrinsic");
          }
          const auto size = intrinsic.attr("get_focal_length")().cast<std::pair<double, double>>();
          const auto centre = intrinsic.attr("get_principal_point")().cast<std::pair<double, double>>();
          PinholeIntrinsics k;
          k.fx = size.first;
          k.fy = size.second;
          k.cx = centre.first;
          k.cy = centre.second;
          k.width = intrinsic.attr("width").cast<int>();
          k.height = intrinsic.attr("height").cast<int>();
          CameraOptions c = WithIntrinsics(camera, k);
          std::string why;
          if (!c.IsValid(&why)) throw py::value_error("camera_from_open3d: " + why);
          return c;
        },
        py::arg("intrinsic"), py::arg("camera") = py::none(),
        "A CameraOptions with the intrinsics of an open3d.camera.PinholeCameraIntrinsic and the "
        "pose of `camera` (default: the camera frame is the scene frame).");

  // ---- TUM RGB-D sequences ---------------------------------------------------------------
  m.attr("TUM_DEPTH_SCALE") = kTumDepthScale;
  py::class_<TumFrame>(m, "TumFrame", "One line of a TUM RGB-D list.")
      .def_readonly("time", &TumFrame::time, "the depth image's timestamp (s)")
      .def_readonly("depth", &TumFrame::depth, "the depth image's path")
      .def_readonly("rgb_time", &TumFrame::rgb_time, "the colour image's timestamp (0 from depth.txt)")
      .def_readonly("rgb", &TumFrame::rgb, "the colour image's path ('' from depth.txt)")
      .def_readonly("line", &TumFrame::line, "the line of the list (1-based)")
      .def("__repr__", [](const TumFrame& f) {
        return "<femreg.TumFrame " + std::to_string(f.time) + " " + f.depth + ">";
      });
  py::class_<TumSequence>(m, "TumSequence", "The frames of a TUM RGB-D list, in its order.")
      .def_readonly("list", &TumSequence::list, "the list read")
      .def_readonly("frames", &TumSequence::frames)
      .def_property_readonly("depth_files", [](const TumSequence& s) {
        std::vector<std::string> files;
        for (const TumFrame& f : s.frames) files.push_back(f.depth);
        return files;
      })
      .def_property_readonly("depth_scale", [](const TumSequence&) { return kTumDepthScale; },
                             "metres per depth unit: 1/5000")
      .def("__len__", [](const TumSequence& s) { return s.frames.size(); })
      .def("__repr__", [](const TumSequence& s) {
        return "<femreg.TumSequence " + std::to_string(s.frames.size()) + " frames from " + s.list + ">";
      });
  m.def("read_tum_sequence",
        [](const std::string& path) {
          TumSequence sequence;
          Check(ReadTumSequence(path, &sequence));
          return sequence;
        },
        py::arg("path"),
        "A TUM RGB-D sequence: a folder holding associations.txt (or association.txt, "
        "associate.txt, depth.txt), or such a list. femreg.Error names the list and the line of "
        "a bad line or a missing depth image.");

  // ---- the frames of a recording ---------------------------------------------------------
  m.def("list_frames",
        [](const std::string& path) {
          FrameFiles frames;
          Check(ListFrameFiles(path, &frames));
          py::dict info;
          info["tum_list"] = frames.tum_list.empty() ? py::object(py::none()) : py::str(frames.tum_list);
          info["depth_scale"] = frames.depth_scale > 0 ? py::object(py::float_(frames.depth_scale))
                                                       : py::object(py::none());
          info["times"] = frames.times.empty() ? py::object(py::none()) : py::cast(frames.times);
          return py::make_tuple(frames.files, info);
        },
        py::arg("path"),
        "The frames `femreg register --frames PATH` reads, in order: a TUM RGB-D sequence's "
        "depth images in its list's order, a folder's clouds and depth images (.pcd, .ply, "
        ".xyz, .txt, .png, .npy) in natural order, or a glob pattern's matches. Returns (files, "
        "info); info has tum_list, depth_scale (the layout's metres per unit: TUM's 1/5000, or "
        "None) and times (TUM timestamps, or None).");
  m.def("read_frame",
        [](const std::string& path, const CameraOptions& camera, double depth_scale,
           double min_depth, double max_depth, int pixel_stride, const std::string& mask_dir) {
          return ReadFrameWith([](const std::string& p, const CameraOptions& c, const DepthImageOptions& o,
                                  PointCloud* cloud) { return ReadFrame(p, c, o, cloud); },
                               path, camera, depth_scale, min_depth, max_depth, pixel_stride, mask_dir);
        },
        py::arg("path"), py::arg("camera"), py::arg("depth_scale") = 0.001,
        py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0, py::arg("pixel_stride") = 1,
        py::arg("mask_dir") = "",
        "A frame as `femreg register` reads it: a depth image (.png, .npy) back-projected "
        "through the camera (masked by mask_dir/NAME.png when given), any other file as a "
        "point cloud. A PointCloud.");
}

}  // namespace python
}  // namespace femreg
