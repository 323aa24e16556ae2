// The library in a few calls: load a scene, build a Tracker, Track once per cloud, read
// the deformed vertices and the frame summary.
//   track_sequence SCENE.yaml CLOUD [CLOUD ...]
#include <femreg/point_cloud.h>
#include <femreg/scene.h>
#include <femreg/tracker.h>

#include <cstdio>
#include <memory>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCENE.yaml CLOUD [CLOUD ...]\n", argv[0]);
    return 2;
  }
  femreg::Scene scene;
  femreg::Status status = femreg::LoadScene(argv[1], &scene);
  if (!status.ok()) {
    std::fprintf(stderr, "%s\n", status.message().c_str());
    return 1;
  }
  std::unique_ptr<femreg::Tracker> tracker;
  status = femreg::Tracker::Create(scene, &tracker);
  if (!status.ok()) {
    std::fprintf(stderr, "%s\n", status.message().c_str());
    return 1;
  }
  for (int i = 2; i < argc; ++i) {
    femreg::PointCloud cloud;  // in your tracker: fill cloud.points from the camera
    status = femreg::ReadPointCloud(argv[i], &cloud);
    if (!status.ok()) std::fprintf(stderr, "%s (tracked as an empty frame)\n", status.message().c_str());
    femreg::FrameSummary summary;
    tracker->Track(cloud, &summary);
    std::printf("%s\n", summary.BriefReport().c_str());
    if (summary.IsSolutionUsable()) {
      const femreg::Vertices& x = tracker->vertices(0);  // #V by 3, metres
      std::printf("  vertex 0 at (%.4f, %.4f, %.4f)\n", x(0, 0), x(0, 1), x(0, 2));
    }
  }
  return 0;
}
