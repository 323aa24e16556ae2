// The helpers the binding files share (bindings.h): Status to femreg.Error, numpy arrays to
// and from Vertices, depth images and masks from numpy.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "bindings.h"

namespace femreg {
namespace python {

void Check(const Status& status) {
  if (!status.ok()) throw Error(status.message());
}

// An (N, 3) float array as Vertices; `what` names the argument in the ValueError.
void CopyRows3(const DoubleArray& array, const char* what, Vertices* out) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < array.ndim(); ++i) {
      shape += (i ? ", " : "") + std::to_string(array.shape(i));
    }
    throw py::value_error(std::string(what) + ": expected an (N, 3) array, got shape " + shape +
                          (array.ndim() == 1 ? ",)" : ")"));
  }
  const py::ssize_t n = array.shape(0);
  out->resize(n, 3);
  if (n == 0) return;
  // Vertices is row-major: a C-contiguous array is one memcpy.
  if (array.flags() & py::array::c_style) {
    std::memcpy(out->data(), array.data(), static_cast<size_t>(n) * 3 * sizeof(double));
  } else {
    auto a = array.unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) (*out)(i, k) = a(i, k);
    }
  }
}

py::array_t<double> ToArray(const Vertices& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.rows()), static_cast<py::ssize_t>(3)});
  if (v.rows() > 0) {
    std::memcpy(out.mutable_data(), v.data(), static_cast<size_t>(v.rows()) * 3 * sizeof(double));
  }
  return out;
}

bool IsOpen3d(const py::handle& obj, const char* name) {
  const py::handle type = reinterpret_cast<PyObject*>(Py_TYPE(obj.ptr()));
  if (!py::hasattr(type, "__module__")) return false;
  const std::string module = py::str(type.attr("__module__"));
  if (module.rfind("open3d", 0) != 0) return false;
  const py::module_ open3d = py::module_::import("open3d");
  const char* part = std::string(name) == "PinholeCameraIntrinsic" ? "camera" : "geometry";
  return py::isinstance(obj, open3d.attr(part).attr(name));
}

DoubleArray PointsArg(const py::object& points, py::object* normals) {
  if (IsOpen3d(points, "PointCloud")) {
    const py::module_ numpy = py::module_::import("numpy");
    if (normals != nullptr && normals->is_none() && points.attr("has_normals")().cast<bool>()) {
      *normals = numpy.attr("asarray")(points.attr("normals"));
    }
    return numpy.attr("asarray")(points.attr("points")).cast<DoubleArray>();
  }
  DoubleArray array = DoubleArray::ensure(points);  // null (the error cleared) when not numbers
  if (!array) {
    throw py::type_error("points: expected an (N, 3) array of numbers or an "
                         "open3d.geometry.PointCloud (got " +
                         py::str(py::type::handle_of(points).attr("__name__")).cast<std::string>() + ")");
  }
  return array;
}

// Float depths beyond this are not metres of a depth camera: most likely depth units (a
// float array of millimetres), which would put every point kilometres away.
constexpr double kMaxMetres = 100.0;

void ToRawDepth(const py::object& depth, RawDepthImage* image) {
  py::object array = depth;
  if (IsOpen3d(depth, "RGBDImage")) {
    array = depth.attr("depth");  // an open3d.geometry.Image of float metres
  }
  if (IsOpen3d(array, "Image")) array = py::module_::import("numpy").attr("asarray")(array);
  const py::array a = py::array::ensure(array);
  if (!a || a.ndim() != 2) {
    throw py::value_error("depth: expected an (H, W) array of depth units (integers) or metres "
                          "(floats), or an Open3D Image or RGBDImage");
  }
  image->height = static_cast<int>(a.shape(0));
  image->width = static_cast<int>(a.shape(1));
  image->values.clear();
  image->metres.clear();
  if (a.dtype().kind() == 'f') {
    const auto m = a.cast<py::array_t<float, py::array::forcecast>>();
    auto d = m.unchecked<2>();
    image->metres.resize(static_cast<size_t>(m.size()));
    size_t i = 0;
    float largest = 0;
    for (py::ssize_t v = 0; v < m.shape(0); ++v) {
      for (py::ssize_t u = 0; u < m.shape(1); ++u) {
        const float z = d(v, u);
        image->metres[i++] = z;
        if (std::isfinite(z) && z > largest) largest = z;
      }
    }
    if (largest > kMaxMetres) {
      throw py::value_error("depth: a float array holds metres, and this one reaches " +
                            std::to_string(largest) + " m; for depth units (millimetres, say) pass "
                            "integers (e.g. depth.astype(numpy.uint16)) with depth_scale");
    }
    return;
  }
  const auto units = a.cast<py::array_t<uint16_t, py::array::forcecast>>();
  auto d = units.unchecked<2>();
  image->values.resize(static_cast<size_t>(units.size()));
  size_t i = 0;
  for (py::ssize_t v = 0; v < units.shape(0); ++v) {
    for (py::ssize_t u = 0; u < units.shape(1); ++u) image->values[i++] = d(v, u);
  }
}

// An optional (H, W) mask (non-zero = keep) as flags.
bool ToKeep(const py::object& mask, const RawDepthImage& image, std::vector<uint8_t>* keep) {
  if (mask.is_none()) return false;
  auto m = mask.cast<py::array_t<uint8_t, py::array::forcecast>>();
  if (m.ndim() != 2 || m.shape(0) != image.height || m.shape(1) != image.width) {
    throw py::value_error("mask: expected an (H, W) array the size of the depth image (" +
                          std::to_string(image.height) + ", " + std::to_string(image.width) + ")");
  }
  keep->resize(static_cast<size_t>(m.size()));
  auto a = m.unchecked<2>();
  size_t i = 0;
  for (py::ssize_t v = 0; v < m.shape(0); ++v) {
    for (py::ssize_t u = 0; u < m.shape(1); ++u) (*keep)[i++] = a(v, u) != 0;
  }
  return true;
}

PointCloud ReadFrameWith(FrameReader read, const std::string& path, const CameraOptions& camera,
                         double depth_scale, double min_depth, double max_depth, int pixel_stride,
                         const std::string& mask_dir) {
  DepthImageOptions options = MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride);
  options.mask_dir = mask_dir;
  PointCloud cloud;
  Check(read(path, camera, options, &cloud));
  return cloud;
}

DepthImageOptions MakeDepthOptions(double depth_scale, double min_depth, double max_depth,
                                   int pixel_stride) {
  DepthImageOptions o;
  o.depth_scale = depth_scale;
  o.min_depth = min_depth;
  o.max_depth = max_depth;
  o.pixel_stride = pixel_stride;
  std::string why;
  if (!o.IsValid(&why)) throw py::value_error(why);
  return o;
}

}  // namespace python
}  // namespace femreg
