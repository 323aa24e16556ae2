// femreg register's checks and measurements beside the tracking: the scene keys register
// does not use, the meshes' extent and the units hint, and the contact meter of
// --no-collision.
#ifndef FEMREG_TOOLS_REGISTER_CHECKS_H_
#define FEMREG_TOOLS_REGISTER_CHECKS_H_

#include <string>
#include <vector>

#include "femreg/collision.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/status.h"
#include "femreg/tracker.h"

namespace femreg {
namespace cli {
namespace register_checks {

// With --no-collision: the scene's collision section used only to measure, after each frame,
// the contacts and the deepest penetration of the result (the tracker adds no contact term).
class ContactMeter {
 public:
  Status Init(const Scene& scene, const Tracker& tracker) {
    std::vector<std::string> names;
    for (const ObjectSpec& o : scene.objects) names.push_back(o.name);
    Gather(tracker);
    return world_.Init(scene.collision, names, surfaces_, x_);  // no pairs: every pair
  }
  void Measure(const Tracker& tracker, int frame, FrameSummary* s) {
    const Eigen::Index before = x_.rows();
    Gather(tracker);
    if (x_.rows() != before) {  // fracture changed the topology
      for (size_t i = 0; i < surfaces_.size(); ++i) world_.Rebuild(static_cast<int>(i), surfaces_[i], x_);
    }
    world_.SetFrame(frame);
    std::vector<Contact> contacts;
    world_.Detect(x_, 0.0, &contacts);
    const ContactStats cs = world_.Evaluate(contacts, x_);
    s->contacts = cs.contacts;
    s->object_contacts = cs.object_contacts;
    s->obstacle_contacts = cs.obstacle_contacts;
    s->max_penetration = cs.max_penetration;
    s->min_gap = cs.min_gap;
  }
  double distance() const { return world_.distance(); }
  double tolerance() const { return world_.tolerance(); }

 private:
  // All objects' vertices and surfaces in one numbering, as the tracker's world has them.
  void Gather(const Tracker& tracker) {
    int n = 0;
    for (int i = 0; i < tracker.num_objects(); ++i) n += tracker.mesh(i).num_vertices();
    x_.resize(n, 3);
    surfaces_.clear();
    int offset = 0;
    for (int i = 0; i < tracker.num_objects(); ++i) {
      const TetMesh& m = tracker.mesh(i);
      x_.middleRows(offset, m.num_vertices()) = tracker.vertices(i);
      surfaces_.push_back(m.surface.array() + offset);
      offset += m.num_vertices();
    }
  }
  CollisionWorld world_;
  Vertices x_;
  std::vector<Triangles> surfaces_;
};

// Scene keys that register would not use are refused, naming the key and what to use.
// Clamps in `boundary` are used: Tracker::Create(scene) makes them hard anchors; gravity
// and loads act in the registration energy (registration.loads).
Status CheckRegisterKeys(const Scene& scene);

// The diagonal of the meshes' rest bounding box (m).
double MeshExtent(const Tracker& tracker);

// The mean length of the meshes' surface edges (m).
double MeshMeanEdge(const Tracker& tracker);

// The median distance from a point of `cloud` to its nearest other point, over up to 200
// points spread over the cloud; 0 with fewer than two distinct points.
double MedianSpacing(const PointCloud& cloud);

// The units hint, once, on the first frame's points as the tracker uses them (`used`,
// PrepareCloudForTracking: after the mask, preprocess.scale and transform, the crop, the plane
// removal and the outlier filter), not the frame as read: a depth image of the whole room
// around a masked or cropped object is no units mistake. When their extent and the meshes'
// differ by more than 10 times, it says what it compared (the bounding box diagonals, the
// points' median spacing and the meshes' mean edge) and which it suspects: a cloud larger than
// the meshes whose points are closer than 10 mesh edges holds more than the objects (a note:
// mask or crop it); otherwise the units differ (a warning: "Different units?").
void WarnUnits(const std::string& file, const PointCloud& used, const Tracker& tracker);

}  // namespace register_checks
}  // namespace cli
}  // namespace femreg

#endif  // FEMREG_TOOLS_REGISTER_CHECKS_H_
