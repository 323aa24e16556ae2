// What the femreg Python module's translation units share: femreg.Error and Check, numpy
// (N, 3) arrays in and out, enum fields as string properties, depth images from numpy, and
// the Bind* functions that femreg_module.cc's module init calls in order (a class is bound
// before the functions whose signatures name it).
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "femreg/mesh.h"
#include "femreg/option_fields.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"

namespace py = pybind11;

namespace femreg {
namespace python {

// Raised for every femreg::Status error (registered as femreg.Error, a RuntimeError).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void Check(const Status& status);

using DoubleArray = py::array_t<double, py::array::forcecast>;

// An (N, 3) float array as Vertices; `what` names the argument in the ValueError.
void CopyRows3(const DoubleArray& array, const char* what, Vertices* out);

py::array_t<double> ToArray(const Vertices& v);

template <typename Enum>
Enum EnumFromString(const std::string& s, const std::string& field) {
  Enum v;
  if (!FromString(s, &v)) {
    std::string names;
    for (Enum e : EnumValues<Enum>::kAll) names += (names.empty() ? "" : ", ") + std::string(ToString(e));
    throw py::value_error(field + ": unknown value '" + s + "' (use " + names + ")");
  }
  return v;
}

// Binds an enum field of a struct as a string property; `qualified` names it in messages.
template <typename Class, typename Struct, typename Enum>
void EnumProperty(Class& cls, const char* name, Enum Struct::*field, std::string qualified,
                  const char* doc) {
  cls.def_property(
      name, [field](const Struct& s) { return std::string(ToString(s.*field)); },
      [field, qualified](Struct& s, const std::string& v) {
        s.*field = EnumFromString<Enum>(v, qualified);
      },
      doc);
}

// Binds an optional enum field (a value a scene may leave unset) as a string property that
// is None when unset and takes None to unset it.
template <typename Class, typename Struct, typename Enum>
void OptionalEnumProperty(Class& cls, const char* name, std::optional<Enum> Struct::*field,
                          std::string qualified, const char* doc) {
  cls.def_property(
      name,
      [field](const Struct& s) -> py::object {
        return (s.*field).has_value() ? py::object(py::str(ToString(*(s.*field)))) : py::object(py::none());
      },
      [field, qualified](Struct& s, const py::object& v) {
        if (v.is_none()) {
          s.*field = std::nullopt;
        } else {
          s.*field = EnumFromString<Enum>(v.cast<std::string>(), qualified);
        }
      },
      doc);
}

// A field's value as Python shows it: an enum by its name, a Vector3d as a list of floats, an
// unset optional as None.
template <typename T>
py::object FieldObject(const T& value) {
  if constexpr (FieldType<T>::kOptional) {
    return value.has_value() ? FieldObject(*value) : py::object(py::none());
  } else if constexpr (std::is_enum_v<T>) {
    return py::str(ToString(value));
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return py::cast(std::vector<double>{value.x(), value.y(), value.z()});
  } else {
    return py::cast(value);
  }
}

// An options object takes only the attributes its class has: a misspelt or renamed one
// (`solver.thread = 1`) raises AttributeError naming the ones there are.
template <typename Class>
void RefuseUnknownAttributes(Class& cls) {
  cls.def("__setattr__", [](const py::object& self, const std::string& name, const py::object& value) {
    const py::object type = py::type::of(self);
    // A Python subclass's instances have a __dict__ of their own: their attributes are theirs.
    if (!py::hasattr(type, name.c_str()) && !py::hasattr(self, "__dict__")) {
      const py::object property = py::module_::import("builtins").attr("property");
      std::string names;
      for (const auto& item : py::module_::import("builtins").attr("dir")(type)) {
        const std::string n = py::str(item);
        if (n.empty() || n[0] == '_' || !py::isinstance(type.attr(n.c_str()), property)) continue;
        names += (names.empty() ? "" : ", ") + n;
      }
      throw py::attribute_error(type.attr("__name__").cast<std::string>() + " has no attribute '" + name +
                                "' (its attributes: " + names + ")");
    }
    py::module_::import("builtins").attr("object").attr("__setattr__")(self, name, value);
  });
}

// Binds every field of an options table (femreg/option_fields.h) under its Python name:
// flags and numbers as attributes, enums as string properties ("data.loss" in messages), a
// value the scene may leave unset (std::optional) as None when it is.
template <typename Class>
void DefFields(Class& cls) {
  RefuseUnknownAttributes(cls);
  using Options = typename Class::type;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    using Field = std::decay_t<decltype(std::declval<Options&>().*member)>;
    using T = typename FieldType<Field>::Value;
    if constexpr (std::is_enum_v<T> && FieldType<Field>::kOptional) {
      OptionalEnumProperty(cls, f.python_name(), member, FieldName<Options>(f), f.doc);
    } else if constexpr (std::is_enum_v<T>) {
      EnumProperty(cls, f.python_name(), member, FieldName<Options>(f), f.doc);
    } else {
      cls.def_readwrite(f.python_name(), member, f.doc);
    }
  });
}

// Binds every field of a table as a property whose setter checks the struct with the new
// value (`valid`: the table's ranges and any rule across fields, as the scene parser checks
// them; `field` is the name of the field just set, for a rule across fields to name it); a
// bad value raises ValueError with valid's message and leaves the struct as it was. Enums
// and unset optionals read and take strings and None; a vector reads as a list.
template <typename Class>
void DefCheckedFields(Class& cls,
                      bool (*valid)(const typename Class::type&, const std::string& field, std::string*)) {
  RefuseUnknownAttributes(cls);
  using Options = typename Class::type;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    using Field = std::decay_t<decltype(std::declval<Options&>().*member)>;
    using T = typename FieldType<Field>::Value;
    const std::string name = FieldName<Options>(f);
    cls.def_property(
        f.python_name(), [member](const Options& o) { return FieldObject(o.*member); },
        [member, name, valid](Options& o, const py::object& value) {
          const Field old = o.*member;
          if constexpr (std::is_enum_v<T>) {
            if (FieldType<Field>::kOptional && value.is_none()) {
              o.*member = Field();  // None: unset
            } else {
              o.*member = EnumFromString<T>(value.cast<std::string>(), name);
            }
          } else {
            try {
              o.*member = value.cast<Field>();
            } catch (const py::cast_error&) {
              throw py::type_error(name + ": cannot take " + py::repr(value).template cast<std::string>());
            }
          }
          std::string why;
          if (!valid(o, name, &why)) {
            o.*member = old;
            throw py::value_error(why);
          }
        },
        f.doc);
  });
}

// "youngs_modulus=100000.0, poisson_ratio=0.3, density=1000.0": every field of a table.
template <typename Options>
std::string FieldsRepr(const Options& o) {
  std::string fields;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    fields += std::string(fields.empty() ? "" : ", ") + f.python_name() + "=" +
              py::repr(FieldObject(o.*member)).template cast<std::string>();
  });
  return fields;
}

// A constructor and __repr__ from an options table: Name(field=default, ...) takes every
// field by its Python name (positional ones in the table's order), each defaulting to the
// struct's default; an unknown or repeated name raises TypeError; `valid` (the struct's
// IsValid, or its table's ranges) raises ValueError naming the field. The docstring lists
// the keywords with their defaults.
template <typename Class>
void DefFieldsInit(Class& cls, const char* name,
                   bool (*valid)(const typename Class::type&, std::string*) =
                       &CheckFieldRanges<typename Class::type>) {
  using Options = typename Class::type;
  static const std::string doc = std::string(name) + "(" + FieldsRepr(Options()) + ")";
  const std::string type = name;
  cls.def(py::init([type, valid](const py::args& args, const py::kwargs& kwargs) {
            Options o;
            std::vector<std::string> names;
            OptionFields<Options>::Visit([&](auto, const FieldInfo& f) { names.push_back(f.python_name()); });
            if (args.size() > names.size()) {
              throw py::type_error(type + "() takes at most " + std::to_string(names.size()) +
                                   " positional arguments (got " + std::to_string(args.size()) + ")");
            }
            for (const auto& item : kwargs) {
              const std::string key = py::str(item.first);
              if (std::find(names.begin(), names.end(), key) == names.end()) {
                std::string accepted;
                for (const std::string& n : names) accepted += (accepted.empty() ? "" : ", ") + n;
                throw py::type_error(type + "(): unexpected keyword argument '" + key + "' (one of: " + accepted + ")");
              }
            }
            size_t i = 0;
            OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
              py::object value;
              if (i < args.size()) value = args[i];
              ++i;
              if (kwargs.contains(f.python_name())) {
                if (value) throw py::type_error(type + "(): got multiple values for '" + f.python_name() + "'");
                value = kwargs[f.python_name()];
              }
              if (!value) return;
              using Field = std::decay_t<decltype(o.*member)>;
              using T = typename FieldType<Field>::Value;
              if constexpr (std::is_enum_v<T>) {
                if (FieldType<Field>::kOptional && value.is_none()) {
                  o.*member = Field();  // None: unset
                } else {
                  o.*member = EnumFromString<T>(value.template cast<std::string>(), FieldName<Options>(f));
                }
              } else {  // an optional takes None
                try {
                  o.*member = value.template cast<Field>();
                } catch (const py::cast_error&) {
                  throw py::type_error(type + "(): " + f.python_name() + ": cannot take " +
                                       py::repr(value).template cast<std::string>());
                }
              }
            });
            std::string why;
            if (!valid(o, &why)) throw py::value_error(type + ": " + why);
            return o;
          }),
          doc.c_str());
  cls.def("__repr__", [type](const Options& o) { return type + "(" + FieldsRepr(o) + ")"; });
}

// Open3D's objects, accepted without depending on Open3D: true when `obj` is an instance
// of open3d.geometry.<name> (or open3d.camera.<name> for "PinholeCameraIntrinsic"). Open3D
// is imported only to check an object whose type comes from it, so a caller without Open3D
// never loads it.
bool IsOpen3d(const py::handle& obj, const char* name);

// The points of an (N, 3) array or of an open3d.geometry.PointCloud (whose normals fill
// *normals when it has them and *normals is None).
DoubleArray PointsArg(const py::object& points, py::object* normals);

// A depth image as a RawDepthImage: an (H, W) integer array of depth units (0 = no
// return), an (H, W) float array of metres (0 or NaN = no return), an open3d.geometry.Image
// of either, or an open3d.geometry.RGBDImage (its depth, float metres).
void ToRawDepth(const py::object& depth, RawDepthImage* image);

// An optional (H, W) mask (non-zero = keep) as flags.
bool ToKeep(const py::object& mask, const RawDepthImage& image, std::vector<uint8_t>* keep);

DepthImageOptions MakeDepthOptions(double depth_scale, double min_depth, double max_depth,
                                   int pixel_stride);

// One frame file read through the camera by `read` (ReadFrame, ReadDepthFrame) with a
// binding's depth arguments (MakeDepthOptions, mask_dir).
using FrameReader = Status (*)(const std::string& path, const CameraOptions& camera,
                               const DepthImageOptions& options, PointCloud* cloud);
PointCloud ReadFrameWith(FrameReader read, const std::string& path, const CameraOptions& camera,
                         double depth_scale, double min_depth, double max_depth, int pixel_stride,
                         const std::string& mask_dir);

// The bindings, by file, in the order the module init calls them.
void BindOptions(py::module_& m);      // options_bindings.cc: Material and the options structs
void BindMeshes(py::module_& m);       // io_bindings.cc: Mesh, mesh readers and writers
void BindPointClouds(py::module_& m);  // io_bindings.cc: PointCloud, cloud readers and writers
void BindDepthImages(py::module_& m);  // io_bindings.cc: depth PNGs, back-projection
void BindCameraFiles(py::module_& m);  // camera_bindings.cc: .npy, intrinsics, TUM, frame lists
void BindScene(py::module_& m);        // scene_bindings.cc: Scene, load_scene, parse_scene
void BindTracker(py::module_& m);      // tracker_bindings.cc: Tracker and its summaries
void BindSimulate(py::module_& m);     // scene_bindings.cc: the forward solve

}  // namespace python
}  // namespace femreg
