// The helpers the binding files share (bindings.h): Status to femreg.Error, numpy arrays to
// and from Vertices, depth images and masks from numpy.
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

// An (H, W) integer array as a RawDepthImage (values in depth units, 0 = no return).
void ToRawDepth(const py::array_t<uint16_t, py::array::forcecast>& depth, RawDepthImage* image) {
  if (depth.ndim() != 2) throw py::value_error("depth: expected an (H, W) array of depth units");
  image->height = static_cast<int>(depth.shape(0));
  image->width = static_cast<int>(depth.shape(1));
  image->values.resize(static_cast<size_t>(depth.size()));
  auto d = depth.unchecked<2>();
  size_t i = 0;
  for (py::ssize_t v = 0; v < depth.shape(0); ++v) {
    for (py::ssize_t u = 0; u < depth.shape(1); ++u) image->values[i++] = d(v, u);
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
