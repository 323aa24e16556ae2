// Python bindings: meshes (read, from arrays, boxes; VTU, PLY and OBJ writers), point clouds
// (PCD, PLY, text) and depth images (16-bit PNGs, back-projection through a camera).
#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg/point_cloud.h"

namespace femreg {
namespace python {

void BindMeshes(py::module_& m) {
  // ---- meshes ---------------------------------------------------------------------------
  py::class_<TetMesh>(m, "Mesh", "A tetrahedral mesh; arrays are read-only views of it.")
      .def_property_readonly("rest", [](const TetMesh& t) -> const Vertices& { return t.rest; },
                             py::return_value_policy::reference_internal, "#V by 3 rest positions")
      .def_property_readonly("x", [](const TetMesh& t) -> const Vertices& { return t.x; },
                             py::return_value_policy::reference_internal,
                             "#V by 3 current positions")
      .def_property_readonly("tets", [](const TetMesh& t) -> const Tets& { return t.tets; },
                             py::return_value_policy::reference_internal, "#T by 4 vertex indices")
      .def_property_readonly("surface", [](const TetMesh& t) -> const Triangles& { return t.surface; },
                             py::return_value_policy::reference_internal,
                             "#F by 3 boundary triangles, counter-clockwise seen from outside")
      .def_property_readonly("region", [](const TetMesh& t) -> const Eigen::VectorXi& { return t.region; },
                             py::return_value_policy::reference_internal, "#T region ids")
      .def_property_readonly("mass", [](const TetMesh& t) -> const Eigen::VectorXd& { return t.mass; },
                             py::return_value_policy::reference_internal, "#V lumped masses (kg)")
      .def_property_readonly("surface_vertices", [](const TetMesh& t) { return t.surface_vertices; })
      .def_property_readonly("num_vertices", &TetMesh::num_vertices)
      .def_property_readonly("num_tets", &TetMesh::num_tets)
      .def("set_positions",
           [](TetMesh& t, const DoubleArray& x) {
             Vertices v;
             CopyRows3(x, "positions", &v);
             if (v.rows() != t.rest.rows()) {
               throw py::value_error("positions: " + std::to_string(v.rows()) + " rows for " +
                                     std::to_string(t.rest.rows()) + " vertices");
             }
             t.x = v;
           },
           py::arg("positions"), "Sets the current positions x (#V by 3).")
      .def("__repr__", [](const TetMesh& t) {
        return "<femreg.Mesh " + std::to_string(t.num_vertices()) + " vertices, " +
               std::to_string(t.num_tets()) + " tetrahedra>";
      });

  m.def("read_mesh",
        [](const std::string& path) {
          TetMesh mesh;
          Check(ReadTetMesh(path, &mesh));
          return mesh;
        },
        py::arg("path"),
        "Reads a tetrahedral mesh (Gmsh, TetGen, MEDIT, VTK legacy, VTU; by content).");
  m.def("mesh_from_arrays",
        [](const DoubleArray& vertices, const py::array_t<int, py::array::forcecast>& tets) {
          TetMesh mesh;
          CopyRows3(vertices, "vertices", &mesh.rest);
          if (tets.ndim() != 2 || tets.shape(1) != 4) {
            throw py::value_error("tets: expected a (T, 4) integer array");
          }
          auto t = tets.unchecked<2>();
          mesh.tets.resize(tets.shape(0), 4);
          for (py::ssize_t i = 0; i < tets.shape(0); ++i) {
            for (int k = 0; k < 4; ++k) mesh.tets(i, k) = t(i, k);
          }
          Check(FinalizeMesh(&mesh, "mesh_from_arrays"));
          return mesh;
        },
        py::arg("vertices"), py::arg("tets"),
        "A mesh from (V, 3) positions and (T, 4) vertex indices; checked and oriented.");
  m.def("make_box",
        [](const Eigen::Vector3d& size, const Eigen::Vector3i& cells, const Eigen::Vector3d& origin) {
          if ((cells.array() < 1).any() || (size.array() <= 0).any()) {
            throw py::value_error("make_box: size must be > 0 and cells >= 1");
          }
          return MakeBox(size, cells.x(), cells.y(), cells.z(), origin);
        },
        py::arg("size"), py::arg("cells"), py::arg("origin") = Eigen::Vector3d::Zero(),
        "A box [origin, origin + size] of cells[0] * cells[1] * cells[2] cubes, 6 tets each.");
  m.def("write_vtu",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions,
           const py::dict& fields) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) {
            throw py::value_error("positions: " + std::to_string(x.rows()) + " rows for " +
                                  std::to_string(mesh.rest.rows()) + " vertices");
          }
          std::vector<MeshField> out;
          for (const auto& [key, value] : fields) {
            MeshField f;
            f.name = key.cast<std::string>();
            auto a = value.cast<DoubleArray>();
            const py::ssize_t rows = a.shape(0);
            const py::ssize_t cols = a.ndim() == 1 ? 1 : a.shape(1);
            if (a.ndim() > 2 || (cols != 1 && cols != 3) ||
                (rows != mesh.num_vertices() && rows != mesh.num_tets())) {
              throw py::value_error("fields['" + f.name +
                                    "']: expected one row per vertex or per element with 1 "
                                    "or 3 columns");
            }
            f.per_cell = rows != mesh.num_vertices();
            f.values.resize(rows, cols);
            auto u = a.unchecked();
            for (py::ssize_t i = 0; i < rows; ++i) {
              for (py::ssize_t k = 0; k < cols; ++k) {
                f.values(i, k) = a.ndim() == 1 ? a.at(i) : a.at(i, k);
              }
            }
            (void)u;
            out.push_back(std::move(f));
          }
          Check(WriteVtu(path, mesh, x, out));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        py::arg("fields") = py::dict(),
        "Writes the mesh at `positions` (default mesh.x) as VTU with point or cell fields "
        "({name: (V,) / (V, 3) / (T,) / (T, 3) array}); atomic.");
  m.def("write_ply_surface",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) throw py::value_error("positions: wrong row count");
          Check(WritePlySurface(path, mesh, x));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        "Writes the boundary surface as ASCII PLY; atomic.");
  m.def("write_obj_surface",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) throw py::value_error("positions: wrong row count");
          Check(WriteObjSurface(path, mesh, x));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        "Writes the boundary surface as OBJ; atomic.");
}

void BindPointClouds(py::module_& m) {
  // ---- point clouds ---------------------------------------------------------------------
  py::class_<PointCloud>(m, "PointCloud", "Points (metres, scene frame), optional normals and labels.")
      .def(py::init([](const py::object& points_arg, py::object normals) {
             PointCloud c;
             CopyRows3(PointsArg(points_arg, &normals), "points", &c.points);
             if (!normals.is_none()) {
               CopyRows3(normals.cast<DoubleArray>(), "normals", &c.normals);
               if (c.normals.rows() != c.points.rows()) {
                 throw py::value_error("normals: one row per point expected");
               }
             }
             return c;
           }),
           py::arg("points"), py::arg("normals") = py::none(),
           "From (N, 3) points (and normals), or from an open3d.geometry.PointCloud (with its "
           "normals when it has them).")
      .def_property_readonly("points", [](const PointCloud& c) -> const Vertices& { return c.points; },
                             py::return_value_policy::reference_internal)
      .def_property_readonly("normals",
                             [](py::object self) -> py::object {
                               const PointCloud& c = self.cast<const PointCloud&>();
                               if (!c.has_normals()) return py::none();
                               return py::cast(c.normals, py::return_value_policy::reference_internal, self);
                             })
      .def_property_readonly("labels",
                             [](py::object self) -> py::object {
                               const PointCloud& c = self.cast<const PointCloud&>();
                               if (!c.has_labels()) return py::none();
                               return py::cast(c.labels, py::return_value_policy::reference_internal, self);
                             })
      .def("__len__", &PointCloud::size)
      .def("__repr__", [](const PointCloud& c) {
        return "<femreg.PointCloud " + std::to_string(c.size()) + " points" +
               (c.has_normals() ? ", normals" : "") + (c.has_labels() ? ", labels" : "") + ">";
      });

  m.def("read_point_cloud",
        [](const std::string& path) {
          PointCloud cloud;
          int dropped = 0;
          SensorPose sensor;
          Check(ReadPointCloud(path, &cloud, &dropped, &sensor));
          py::dict info;
          info["nonfinite_dropped"] = dropped;
          info["viewpoint_known"] = sensor.known;
          info["viewpoint"] = Eigen::Vector3d(sensor.origin);
          return py::make_tuple(std::move(cloud), info);
        },
        py::arg("path"),
        "Reads a PCD, PLY or x y z [nx ny nz] text cloud. Returns (PointCloud, info) where "
        "info has nonfinite_dropped, viewpoint_known and viewpoint (the PCD VIEWPOINT origin).");
  m.def("write_point_cloud",
        [](const std::string& path, const py::object& points_arg, py::object normals) {
          PointCloud c;
          CopyRows3(PointsArg(points_arg, &normals), "points", &c.points);
          if (!normals.is_none()) {
            CopyRows3(normals.cast<DoubleArray>(), "normals", &c.normals);
            if (c.normals.rows() != c.points.rows()) {
              throw py::value_error("normals: one row per point expected");
            }
          }
          Check(WritePointCloud(path, c));
        },
        py::arg("path"), py::arg("points"), py::arg("normals") = py::none(),
        "Writes a binary PCD of (N, 3) points or an open3d.geometry.PointCloud (with normals "
        "when given or when it has them); atomic. The path must end in .pcd.");
}

void BindDepthImages(py::module_& m) {
  // ---- depth images --------------------------------------------------------------------
  m.def("read_depth_png",
        [](const std::string& path) {
          RawDepthImage image;
          Check(ReadDepthPng(path, &image));
          py::array_t<uint16_t> out({static_cast<py::ssize_t>(image.height),
                                     static_cast<py::ssize_t>(image.width)});
          std::memcpy(out.mutable_data(), image.values.data(), image.values.size() * sizeof(uint16_t));
          return out;
        },
        py::arg("path"), "A 16-bit greyscale PNG as an (H, W) uint16 array.");
  m.def("write_depth_png",
        [](const std::string& path, const py::object& depth, double depth_scale) {
          RawDepthImage image;
          ToRawDepth(depth, &image);
          if (image.in_metres()) {  // metres to units of depth_scale, rounded
            if (!(depth_scale > 0) || !std::isfinite(depth_scale)) throw py::value_error("depth_scale must be > 0");
            image.values.resize(image.metres.size());
            for (size_t i = 0; i < image.metres.size(); ++i) {
              const float z = image.metres[i];
              const double units = std::isfinite(z) && z > 0 ? std::round(z / depth_scale) : 0.0;
              if (units > 65535) {
                throw py::value_error("depth: " + std::to_string(z) + " m is " + std::to_string(units) +
                                      " units of depth_scale, beyond a 16-bit PNG's 65535");
              }
              image.values[i] = static_cast<uint16_t>(units);
            }
            image.metres.clear();
          }
          Check(WriteDepthPng(path, image));
        },
        py::arg("path"), py::arg("depth"), py::arg("depth_scale") = 0.001,
        "Writes a depth image as a 16-bit PNG, atomically: an (H, W) integer array as it is, "
        "float metres (an array, an Open3D Image or RGBDImage) rounded to units of depth_scale.");
  m.def("depth_to_points",
        [](const py::object& depth, const CameraOptions& camera,
           const py::object& mask, double depth_scale, double min_depth, double max_depth,
           int pixel_stride) {
          RawDepthImage image;
          ToRawDepth(depth, &image);
          std::vector<uint8_t> keep;
          const bool masked = ToKeep(mask, image, &keep);
          PointCloud cloud;
          Check(BackProjectDepth(image, camera,
                                 MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride),
                                 masked ? &keep : nullptr, &cloud));
          return ToArray(cloud.points);
        },
        py::arg("depth"), py::arg("camera"), py::arg("mask") = py::none(),
        py::arg("depth_scale") = 0.001, py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0,
        py::arg("pixel_stride") = 1,
        "Back-projects a depth image through the camera: (N, 3) points in the scene frame. "
        "depth: (H, W) integer depth units (times depth_scale; 0 = no return) or float metres, "
        "or an open3d.geometry.Image or RGBDImage.");
  m.def("read_depth_frame",
        [](const std::string& path, const CameraOptions& camera, double depth_scale,
           double min_depth, double max_depth, int pixel_stride, const std::string& mask_dir) {
          return ReadFrameWith([](const std::string& p, const CameraOptions& c, const DepthImageOptions& o,
                                  PointCloud* cloud) { return ReadDepthFrame(p, c, o, cloud); },
                               path, camera, depth_scale, min_depth, max_depth, pixel_stride, mask_dir);
        },
        py::arg("path"), py::arg("camera"), py::arg("depth_scale") = 0.001,
        py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0, py::arg("pixel_stride") = 1,
        py::arg("mask_dir") = "",
        "A depth frame (a 16-bit .png, or a .npy: float metres or uint16 units) back-projected "
        "through the camera (and masked by mask_dir/NAME.png when mask_dir is given): a "
        "PointCloud.");
}

}  // namespace python
}  // namespace femreg
