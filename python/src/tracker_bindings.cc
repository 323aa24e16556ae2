// Python bindings: the Tracker, with numpy in and out, and its frame summaries as dicts.
//
// The per-frame path (Tracker.track): a C-contiguous float64 (N, 3) array is read in place
// and copied once into the tracker's cloud buffer (femreg::PointCloud owns its points);
// the GIL is released while the frame is solved; the result is one (V, 3) copy of the
// vertices (the tracker overwrites its own next frame).
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"

namespace femreg {
namespace python {
namespace {

py::dict EnergyDict(const EnergyTerms& e) {
  py::dict d;
  d["data"] = e.data;
  d["elastic"] = e.elastic;
  d["temporal"] = e.temporal;
  d["anchor"] = e.anchor;
  d["collision"] = e.collision;
  d["load"] = e.load;
  d["equilibrium"] = e.equilibrium;
  d["total"] = e.total();
  return d;
}

py::dict SummaryDict(const FrameSummary& s) {
  py::dict d;
  d["frame"] = s.frame;
  d["backend"] = ToString(s.backend);
  d["termination"] = ToString(s.termination);
  d["message"] = s.message;
  d["usable"] = s.IsSolutionUsable();
  d["cloud_points"] = s.cloud_points;
  d["nonfinite_dropped"] = s.nonfinite_dropped;
  d["flying_pixels"] = s.flying_pixels;
  d["depth_offset"] = s.depth_offset;
  d["points_used"] = s.points_used;
  d["initial_energy"] = EnergyDict(s.initial);
  d["final_energy"] = EnergyDict(s.final);
  d["outer_iterations"] = s.outer_iterations;
  d["inner_iterations"] = s.inner_iterations;
  d["backtracks"] = s.backtracks;
  d["reversals"] = s.reversals;
  d["large_motion_restarts"] = s.large_motion_restarts;
  d["crushed_restarts"] = s.crushed_restarts;
  d["confidence"] = s.confidence.confidence;
  d["lost"] = s.lost;
  d["confidence_parts"] = py::dict(py::arg("fit") = s.confidence.fit, py::arg("coverage") = s.confidence.coverage,
                                   py::arg("residual") = s.confidence.residual,
                                   py::arg("strain") = s.confidence.strain,
                                   py::arg("volume_change") = s.confidence.volume_change);
  d["stopped_by"] = s.stopped_by;
  d["model_to_cloud"] = s.model_to_cloud;
  d["cloud_to_model"] = s.cloud_to_model;
  d["rejected"] = s.rejected;
  d["occluded_points"] = s.occluded_points;
  d["implausible_points"] = s.implausible_points;
  d["implausible_carried"] = s.implausible_carried;
  d["free_space_vertices"] = s.free_space_vertices;
  d["rms_residual"] = s.rms_residual;
  d["forces_estimated"] = s.forces_estimated;
  d["quiet_start"] = s.quiet_start;
  d["force_weight"] = s.force_weight;
  d["misfit_ratio"] = s.misfit_ratio;
  d["initial_pose"] = s.initial_pose;
  d["pose_ambiguous"] = s.pose_ambiguous;
  d["contacts"] = s.contacts;
  d["object_contacts"] = s.object_contacts;
  d["obstacle_contacts"] = s.obstacle_contacts;
  d["max_penetration"] = s.max_penetration;
  d["min_gap"] = s.min_gap;
  py::list forces;  // per object pair and obstacle: other = -1 - i for obstacle i
  for (const ContactForce& f : s.contact_forces) {
    forces.append(py::dict(py::arg("object") = f.object, py::arg("other") = f.other, py::arg("contacts") = f.contacts,
                           py::arg("force") = Eigen::Vector3d(f.force), py::arg("friction") = Eigen::Vector3d(f.friction)));
  }
  d["contact_forces"] = forces;
  d["force"] = Eigen::Vector3d(s.force);
  d["torque"] = Eigen::Vector3d(s.torque);
  py::dict t;
  t["preprocess"] = s.time.preprocess;
  t["prealign"] = s.time.prealign;
  t["rotations"] = s.time.rotations;
  t["correspondences"] = s.time.correspondences;
  t["build"] = s.time.build;
  t["solve"] = s.time.solve;
  t["collision"] = s.time.collision;
  t["fracture"] = s.time.fracture;
  t["outputs"] = s.time.outputs;
  t["total"] = s.time.total;
  d["time_s"] = t;
  py::list iterations;
  for (const OuterIteration& it : s.iterations) {
    py::dict r;
    r["iteration"] = it.iteration;
    r["energy_before"] = EnergyDict(it.before);
    r["energy_after"] = EnergyDict(it.after);
    r["model_to_cloud"] = it.model_to_cloud;
    r["cloud_to_model"] = it.cloud_to_model;
    r["rejected"] = it.rejected;
    r["inner_iterations"] = it.inner_iterations;
    r["contacts"] = it.contacts;
    r["rms_residual"] = it.rms_residual;
    r["time_s"] = it.time_s;
    iterations.append(r);
  }
  d["iterations"] = iterations;
  py::list fractures;
  for (const FractureEvent& f : s.fractures) {
    py::dict r;
    r["frame"] = f.frame;
    r["object"] = f.object;
    r["iteration"] = f.iteration;
    r["node"] = f.node;
    r["original_node"] = f.original_node;
    r["normal"] = std::vector<double>{f.normal.x(), f.normal.y(), f.normal.z()};
    r["measure"] = f.measure;
    r["toughness"] = f.toughness;
    r["removed_elements"] = f.removed_elements;
    fractures.append(r);
  }
  d["fractures"] = fractures;
  d["report"] = s.BriefReport();
  return d;
}

// A scene and the tracker built from it, with a cloud buffer reused frame after frame.
class PyTracker {
 public:
  explicit PyTracker(std::unique_ptr<Tracker> tracker) : tracker_(std::move(tracker)) {}

  py::array_t<double> Track(const py::object& points_arg, py::object normals,
                            const py::object& labels, int object) {
    CheckObject(object);
    const DoubleArray points = PointsArg(points_arg, &normals);  // an array or an Open3D PointCloud
    CopyRows3(points, "points", &cloud_.points);
    if (normals.is_none()) {
      cloud_.normals.resize(0, 3);
    } else {
      CopyRows3(normals.cast<DoubleArray>(), "normals", &cloud_.normals);
      if (cloud_.normals.rows() != cloud_.points.rows()) {
        throw py::value_error("normals: " + std::to_string(cloud_.normals.rows()) +
                              " rows for " + std::to_string(cloud_.points.rows()) + " points");
      }
    }
    if (labels.is_none()) {
      cloud_.labels.resize(0);
    } else {
      auto l = labels.cast<py::array_t<int, py::array::forcecast>>();
      if (l.ndim() != 1 || l.shape(0) != static_cast<py::ssize_t>(cloud_.points.rows())) {
        throw py::value_error("labels: expected " + std::to_string(cloud_.points.rows()) +
                              " labels (one per point)");
      }
      cloud_.labels = Eigen::Map<const Eigen::VectorXi>(l.data(), l.shape(0));
    }
    return TrackCloud(cloud_, object);
  }

  py::array_t<double> TrackCloud(const PointCloud& cloud, int object) {
    CheckObject(object);
    Status status;
    {
      py::gil_scoped_release release;
      status = tracker_->Track(cloud, &summary_);
    }
    Check(status);
    return ToArray(tracker_->vertices(object));
  }

  void CheckObject(int object) const {
    if (object < 0 || object >= tracker_->num_objects()) {
      throw py::index_error("object " + std::to_string(object) + ": the tracker has " +
                            std::to_string(tracker_->num_objects()) + " object(s)");
    }
  }

  // A depth image through the tracker's camera (options().camera).
  py::array_t<double> TrackDepth(const py::object& depth, const py::object& mask, double depth_scale, double min_depth,
                                 double max_depth, int pixel_stride, int object) {
    CheckObject(object);
    const DepthImageOptions options = MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride);
    ToRawDepth(depth, &depth_);
    std::vector<uint8_t> keep;
    const bool masked = ToKeep(mask, depth_, &keep);
    Check(BackProjectDepth(depth_, tracker_->options().camera, options, masked ? &keep : nullptr,
                           &cloud_));
    return TrackCloud(cloud_, object);
  }

  Tracker& tracker() { return *tracker_; }
  const FrameSummary& summary() const { return summary_; }

 private:
  std::unique_ptr<Tracker> tracker_;
  PointCloud cloud_;  // reused: no allocation when the cloud size does not change
  RawDepthImage depth_;
  FrameSummary summary_;
};

}  // namespace

void BindTracker(py::module_& m) {
  // ---- the tracker ----------------------------------------------------------------------
  py::class_<PyTracker>(m, "Tracker",
                        "Registers the scene's meshes to one point cloud per call.")
      .def(py::init([](const Scene& scene) {
             std::unique_ptr<Tracker> t;
             Check(Tracker::Create(scene, &t));
             return std::make_unique<PyTracker>(std::move(t));
           }),
           py::arg("scene"), "A tracker for every object of a scene (femreg.load_scene).")
      .def(py::init([](const std::vector<TetMesh>& meshes, const std::vector<Material>& materials,
                       const RegistrationOptions& options) {
             if (materials.size() != meshes.size()) {
               throw py::value_error("materials: " + std::to_string(materials.size()) +
                                     " for " + std::to_string(meshes.size()) + " meshes");
             }
             std::vector<ObjectMaterial> object_materials(materials.begin(), materials.end());
             std::unique_ptr<Tracker> t;
             Check(Tracker::Create(meshes, object_materials, options, &t));
             return std::make_unique<PyTracker>(std::move(t));
           }),
           py::arg("meshes"), py::arg("materials"), py::arg("options") = RegistrationOptions(),
           "A tracker for meshes built in code (their x is the initial shape), one Material "
           "per mesh.")
      .def("track", &PyTracker::Track, py::arg("points"), py::arg("normals") = py::none(),
           py::arg("labels") = py::none(), py::arg("object") = 0,
           "Registers to one cloud: points (N, 3) in metres, scene frame, or an "
           "open3d.geometry.PointCloud (its normals used when it has them); optional normals "
           "(N, 3) and labels (N,). Returns object `object`'s (V, 3) vertices (a copy); the "
           "frame summary is in `summary`. Bad data is reported there, never raised.")
      .def("track_depth", &PyTracker::TrackDepth, py::arg("depth"), py::arg("mask") = py::none(),
           py::arg("depth_scale") = 0.001, py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0,
           py::arg("pixel_stride") = 1, py::arg("object") = 0,
           "Registers to a depth image: depth (H, W) integer depth units (times depth_scale; "
           "0 = no return) or float metres (0 or NaN = no return), or an open3d.geometry.Image "
           "or RGBDImage (float metres), back-projected through the scene's camera "
           "(registration.camera); optional mask (H, W), non-zero = keep. Returns the (V, 3) "
           "vertices like track().")
      .def("track_cloud", &PyTracker::TrackCloud, py::arg("cloud"), py::arg("object") = 0,
           "track() for a femreg.PointCloud (e.g. from read_point_cloud or a depth image).")
      .def_property_readonly("summary",
                             [](const PyTracker& t) { return SummaryDict(t.summary()); },
                             "The last frame's summary as a dict.")
      .def_property_readonly("full_report",
                             [](const PyTracker& t) { return t.summary().FullReport(); })
      .def_property_readonly("num_objects", [](PyTracker& t) { return t.tracker().num_objects(); })
      .def_property_readonly("frame", [](PyTracker& t) { return t.tracker().frame(); },
                             "frames tracked so far")
      .def("vertices",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return ToArray(t.tracker().vertices(object));
           },
           py::arg("object") = 0, "(V, 3) current positions (a copy).")
      .def("set_embedded_surface",
           [](PyTracker& t, int object, const DoubleArray& vertices, const Triangles& triangles) {
             t.CheckObject(object);
             Vertices v;
             CopyRows3(vertices, "vertices", &v);
             Check(t.tracker().SetEmbeddedSurface(object, v, triangles));
           },
           py::arg("object"), py::arg("vertices"), py::arg("triangles"),
           "Carries a fine triangle surface (vertices (S, 3) in the object's rest frame, "
           "triangles (F, 3)) by the object's tetrahedra: the data terms act on it "
           "(objects[i].surface in a scene).")
      .def("surface_vertices",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return ToArray(t.tracker().surface_vertices(object));
           },
           py::arg("object") = 0,
           "(S, 3) the object's embedded surface at the current positions (a copy); (0, 3) "
           "without one.")
      .def("surface_triangles",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return Triangles(t.tracker().surface_triangles(object));
           },
           py::arg("object") = 0, "(F, 3) the embedded surface's triangles; (0, 3) without one.")
      .def("external_forces",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return ToArray(t.tracker().external_forces(object));
           },
           py::arg("object") = 0,
           "(V, 3) the external force on each vertex in the last frame (N): the estimated ones "
           "(registration.forces.estimate) and the contacts', zero at clamps and anchors; "
           "without forces.estimate, the data term's pull.")
      .def("mesh",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return t.tracker().mesh(object);
           },
           py::arg("object") = 0, "A copy of the object's mesh (rest data, topology, x).")
      .def("vertex_residuals",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return Eigen::VectorXd(t.tracker().vertex_residuals(object));
           },
           py::arg("object") = 0,
           "(V,) distance (m) to the nearest cloud point in the last frame; NaN inside.")
      .def("vertex_observed",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             const std::vector<char>& o = t.tracker().vertex_observed(object);
             py::array_t<bool> out(static_cast<py::ssize_t>(o.size()));
             for (size_t i = 0; i < o.size(); ++i) out.mutable_at(i) = o[i] != 0;
             return out;
           },
           py::arg("object") = 0, "(V,) whether each vertex had a data partner last frame.")
      .def("set_vertices",
           [](PyTracker& t, int object, const DoubleArray& x) {
             t.CheckObject(object);
             Vertices v;
             CopyRows3(x, "x", &v);
             Check(t.tracker().SetVertices(object, v));
           },
           py::arg("object"), py::arg("x"),
           "Puts the object's vertices at x and starts afresh from there (no velocity, no catch-up or "
           "pose search after a held or lost frame, nothing carried from the last cloud).")
      .def("add_anchor",
           [](PyTracker& t, const std::string& name, int object, const std::vector<int>& vertices,
              bool hard, double weight) {
             Check(t.tracker().AddAnchor(name, object, vertices, hard, weight));
           },
           py::arg("name"), py::arg("object"), py::arg("vertices"), py::arg("hard") = true,
           py::arg("weight") = 0.0)
      .def("set_anchor_targets",
           [](PyTracker& t, const std::string& name, const DoubleArray& targets) {
             Vertices v;
             CopyRows3(targets, "targets", &v);
             Check(t.tracker().SetAnchorTargets(name, v));
           },
           py::arg("name"), py::arg("targets"))
      .def("set_anchor_trajectory",
           [](PyTracker& t, const std::string& name, const DoubleArray& translations,
              const std::optional<DoubleArray>& rotations, const std::array<double, 3>& centre) {
             Vertices tr;
             CopyRows3(translations, "translations", &tr);
             std::vector<Eigen::Vector3d> tv;
             for (Eigen::Index i = 0; i < tr.rows(); ++i) tv.push_back(tr.row(i).transpose());
             if (!rotations) {
               Check(t.tracker().SetAnchorTrajectory(name, tv));
               return;
             }
             Vertices rot;
             CopyRows3(*rotations, "rotations", &rot);
             std::vector<Eigen::Vector3d> rv;
             for (Eigen::Index i = 0; i < rot.rows(); ++i) rv.push_back(rot.row(i).transpose());
             Check(t.tracker().SetAnchorTrajectory(name, tv, rv, Eigen::Vector3d(centre[0], centre[1], centre[2])));
           },
           py::arg("name"), py::arg("translations"), py::arg("rotations") = py::none(),
           py::arg("centre") = std::array<double, 3>{0, 0, 0},
           "Moves the anchored set by translations[frame] (F, 3) from where it was added, after "
           "turning it by rotations[frame] (axis * angle, rad) about centre.")
      .def("set_external_loads",
           [](PyTracker& t, int object, const std::array<double, 3>& gravity,
              const std::optional<std::vector<int>>& vertices, const std::optional<DoubleArray>& forces) {
             t.CheckObject(object);
             std::vector<std::pair<int, Eigen::Vector3d>> nodal;
             if (vertices.has_value() != forces.has_value()) {
               throw py::value_error("set_external_loads: give vertices and forces together");
             }
             if (vertices) {
               Vertices f;
               CopyRows3(*forces, "forces", &f);
               if (static_cast<Eigen::Index>(vertices->size()) != f.rows()) {
                 throw py::value_error("set_external_loads: one force row per vertex");
               }
               for (size_t i = 0; i < vertices->size(); ++i) {
                 nodal.emplace_back((*vertices)[i], f.row(static_cast<Eigen::Index>(i)).transpose());
               }
             }
             Check(t.tracker().SetExternalLoads(object, Eigen::Vector3d(gravity[0], gravity[1], gravity[2]), nodal));
           },
           py::arg("object"), py::arg("gravity"), py::arg("vertices") = py::none(), py::arg("forces") = py::none(),
           "Gravity (m/s^2, on the lumped masses) and nodal forces (N) in the registration energy.")
      .def_property_readonly("options", [](PyTracker& t) { return t.tracker().options(); });
}

}  // namespace python
}  // namespace femreg
