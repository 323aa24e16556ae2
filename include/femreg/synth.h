// femreg/synth.h - the parts synthetic data is made of: a virtual depth camera (pinhole,
// z-buffer, depth noise growing with the square of the depth, dropped pixels at grazing
// angles, outliers, and optional artefacts of real sensors) and the embedding that carries a
// finer mesh's ground truth to the tracked mesh's vertices. The sequence generators that use
// them are in femreg/datasets.h.
#ifndef FEMREG_SYNTH_H_
#define FEMREG_SYNTH_H_

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "femreg/field_table.h"
#include "femreg/geometry.h"
#include "femreg/mesh.h"
#include "femreg/registration.h"
#include "femreg/status.h"

namespace femreg {

// Artefacts of real depth sensors. Each is off at its default and switched on by its
// strength (the first field of each group). Deterministic from the frame's seed, except the
// dark patches and the grazing hole field, which are fixed on the surfaces and the image.
struct SensorArtefacts {
  // Flying pixels: a pixel whose 8 neighbours include one nearer or farther by more than
  // flying_jump returns, with probability flying_fraction, a depth drawn uniformly between
  // its own and that neighbour's, on its own ray.
  double flying_fraction = 0.0;
  double flying_jump = 0.02;  // m
  // Structured-light quantisation: the disparity fx * baseline / z is rounded to a multiple
  // of disparity_step (px), so the depth step grows as z^2 / (fx * baseline).
  double disparity_step = 0.0;  // px; 0 = off
  double baseline = 0.075;      // m, projector to camera
  // Dark surfaces: discs of radius dark_radius fixed on each surface, covering about
  // dark_fraction of its area, return nothing.
  double dark_fraction = 0.0;
  double dark_radius = 0.01;  // m
  // Specular surfaces: no return where the ray meets the surface within specular_angle_deg
  // of its normal (the projector's mirror reflection saturates the pixel).
  double specular_angle_deg = 0.0;  // 0 = off
  // Grazing holes: from grazing_holes_deg of incidence on, pixels drop in blobs: where a
  // smooth image noise field (cells of hole_blob_px pixels, values in [0, 1)) lies below a
  // ramp from 0 at grazing_holes_deg to 1 at grazing_angle_deg.
  double grazing_holes_deg = 0.0;  // 0 = off; lower is stronger
  double hole_blob_px = 6.0;
  // Multipath: depth lengthened by multipath_bias times the fraction of the seen points
  // within multipath_radius that lie in front of the point's tangent plane and face it
  // (0 on a plane or a convex surface, up to 1 deep in a concave corner).
  double multipath_bias = 0.0;  // m
  double multipath_radius = 0.03;  // m
  // Temporal flicker: per frame one depth offset for every pixel (Gaussian, sigma
  // flicker_offset), and a fraction flicker_dropout of the pixels dropped at random.
  double flicker_offset = 0.0;  // m
  double flicker_dropout = 0.0;
  bool IsValid(std::string* error) const;
};

struct DepthSensorOptions {
  CameraOptions camera;                 // position, target, up and intrinsics
  double near = 0.05;                   // m; closer surfaces are not seen
  double noise_coefficient = 2.85e-3;   // sigma_z = k z^2 (1/m); 0 = noiseless
  double grazing_angle_deg = 80.0;      // pixels seeing a surface more obliquely are dropped
  int pixel_stride = 1;                 // sample every k-th pixel in u and v
  double outlier_fraction = 0.0;        // extra uniform outliers, as a fraction of the points
  double outlier_margin = 0.05;         // m around the seen points' bounding box
  SensorArtefacts artefacts;            // all off by default
  bool IsValid(std::string* error) const;
};

// The scene's `synth.sensor:` keys. The camera is registration.camera's; the artefacts have
// their own table (SynthArtefactKeys, femreg/scene.h).
template <>
struct OptionFields<DepthSensorOptions> {
  static constexpr const char* kSection = "sensor";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = DepthSensorOptions;
    v(&S::noise_coefficient, FieldInfo("noise_coefficient").AtLeast(0).Doc("sigma_z = k z^2 (1/m); 0 = noiseless"));
    v(&S::grazing_angle_deg, FieldInfo("grazing_angle_deg").Above(0).AtMost(90).Doc("pixels seeing a surface more obliquely are dropped"));
    v(&S::pixel_stride, FieldInfo("pixel_stride").AtLeast(1).Doc("sample every k-th pixel in u and v"));
    v(&S::outlier_fraction, FieldInfo("outlier_fraction").AtLeast(0).AtMost(10).Doc("extra uniform outliers, a fraction of the points"));
    v(&S::outlier_margin, FieldInfo("outlier_margin").AtLeast(0).Doc("m around the seen points' bounding box"));
    v(&S::near, FieldInfo("near").Above(0).Doc("m; closer surfaces are not seen"));
  }
};

// A triangle surface to render: positions (#V by 3) and triangles (#F by 3).
struct RenderSurface {
  const Vertices* positions = nullptr;
  const Triangles* triangles = nullptr;
  bool returns = true;  // false: hides what is behind it but returns no points (a masked tool)
};

struct DepthImage {
  int width = 0, height = 0;
  std::vector<float> depth;      // row-major, 0 where nothing was hit (z along the axis, m)
  std::vector<int> surface;      // index of the RenderSurface hit, -1 for none
  std::vector<int> triangle;     // triangle hit, -1 for none
};

class DepthSensor {
 public:
  explicit DepthSensor(const DepthSensorOptions& options);

  // Rasterizes the surfaces with a z-buffer (exact, perspective-correct depth).
  DepthImage Render(const std::vector<RenderSurface>& surfaces) const;
  // The cloud the sensor returns for that image: back-projected pixels with noise,
  // grazing-angle drop-outs, outliers and the switched-on artefacts, deterministic from
  // `seed`. The artefacts draw from a generator of their own, after the clean noise is
  // drawn, so switching one on leaves the clean noise of every pixel it keeps unchanged.
  PointCloud Sample(const DepthImage& image, const std::vector<RenderSurface>& surfaces,
                    uint64_t seed) const;
  // Whether each point is seen: in front of the camera, inside the image, and no more
  // than `tolerance` (m) plus two pixel footprints behind the z-buffer's depth at its
  // pixel (at a silhouette, where its pixel sees nothing: the nearest depth around it).
  std::vector<char> Visible(const DepthImage& image, const Vertices& points,
                            double tolerance) const;

  // Camera frame: x right, y down, z forward (OpenCV); p_camera = R (p - position).
  const Eigen::Matrix3d& rotation() const { return R_; }
  bool Project(const Eigen::Vector3d& p, double* u, double* v, double* z) const;
  const DepthSensorOptions& options() const { return options_; }

 private:
  DepthSensorOptions options_;
  Eigen::Matrix3d R_;
};

// femreg synth --depth-png: every clouds_dir/NAME.pcd (points on the camera's pixel rays,
// as the virtual camera returns them) written as depth_dir/NAME.png, the 16-bit depth image
// the camera would store (CloudToDepthImage, femreg/point_cloud.h; depth_scale metres per
// unit). Points two to a pixel (outliers) keep the nearer; points outside the image or
// beyond 65535 units are left out and counted.
struct DepthFramesReport {
  int frames = 0;
  long points = 0;   // cloud points read
  long dropped = 0;  // not in any image
};
Status WriteDepthFrames(const std::string& clouds_dir, const CameraOptions& camera,
                        double depth_scale, const std::string& depth_dir,
                        DepthFramesReport* report);

}  // namespace femreg

#endif  // FEMREG_SYNTH_H_
