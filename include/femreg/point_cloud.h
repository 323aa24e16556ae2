// femreg/point_cloud.h - reading, writing and preprocessing point clouds.
#ifndef FEMREG_POINT_CLOUD_H_
#define FEMREG_POINT_CLOUD_H_

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "femreg/registration.h"
#include "femreg/status.h"

namespace femreg {

// Where the sensor was when it took a cloud, as a PCD file's VIEWPOINT line gives it
// ("VIEWPOINT tx ty tz qw qx qy qz"): the camera centre and its orientation, in the
// cloud's frame.
struct SensorPose {
  bool known = false;  // false: the file has no VIEWPOINT line (PLY, text, or older PCD)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // normalized
};

// Reads PCD (ASCII, binary, binary_compressed; fields x y z of type F required, normal_x
// normal_y normal_z and label used when present), PLY (ASCII or binary, vertex x y z and
// nx ny nz or normal_x normal_y normal_z) or plain text with "x y z" (optionally
// "x y z nx ny nz") per line. Normals are kept when present. Points with a NaN or infinite
// coordinate are dropped and counted in *nonfinite_dropped. Every count and size in a
// header is checked against the file's length before anything is allocated; errors name
// the file and the line (text) or byte offset (binary). *sensor, when given, receives the
// PCD VIEWPOINT.
Status ReadPointCloud(const std::string& path, PointCloud* cloud, int* nonfinite_dropped = nullptr,
                      SensorPose* sensor = nullptr);

// Writes a binary PCD (with normals when the cloud has them), atomically.
Status WritePointCloud(const std::string& path, const PointCloud& cloud);

// Drops non-finite points (counted), then crops, voxel-downsamples, removes statistical
// outliers and estimates normals as the options ask (oriented towards `viewpoint`, the
// camera centre).
void PreprocessPointCloud(const PreprocessOptions& options, PointCloud* cloud,
                          int* nonfinite_dropped = nullptr,
                          const Eigen::Vector3d& viewpoint = Eigen::Vector3d::Zero());

// The cloud as Tracker::Track fits it, before its automatic subsampling (auto_voxel): the
// input transform of options.preprocess (scale, rotation, translation), then
// PreprocessPointCloud oriented towards the camera centre (registration.camera), else the
// cloud's VIEWPOINT. The tracker's own path; `femreg register` writes the result beside the
// meshes and checks its units on it.
void PrepareCloudForTracking(const RegistrationOptions& options, PointCloud* cloud,
                             int* nonfinite_dropped = nullptr);

// Removes points with a non-finite coordinate (or normal); returns how many.
int DropNonFinite(PointCloud* cloud);

// ---------------------------------------------------------------------------------------
// Depth images (depth_image.cc): a frame from a depth camera as a 16-bit PNG whose pixels
// are depths along the optical axis in units of depth_scale (millimetres by default, the
// common sensor convention), 0 where the sensor saw nothing. The camera's intrinsics and
// pose are the scene's (CameraOptions: pixel centres at integer coordinates, x right,
// y down, z forward, as the virtual camera of femreg/synth.h).

struct DepthImageOptions {
  double depth_scale = 0.001;  // metres per depth unit (> 0); 0.001: millimetres
  double min_depth = 0.0;      // m; pixels closer are dropped
  double max_depth = 0.0;      // m; pixels farther are dropped; 0 = no limit
  int pixel_stride = 1;        // back-project every k-th pixel in u and v (>= 1)
  // A folder of masks (PNG, any bit depth or colour; non-zero = keep the pixel) named like
  // the depth frames; empty: no masks. A frame whose mask is missing is an error.
  std::string mask_dir;
  bool IsValid(std::string* error) const;  // names the field
};

// A 16-bit depth image as stored: row-major depth units, 0 = no return.
struct RawDepthImage {
  int width = 0, height = 0;
  std::vector<uint16_t> values;  // width * height
};

// The camera's rotation, world to camera (rows: the image's x, y and optical axes):
// p_camera = R (p - camera.position). The one construction of the camera frame: depth
// images are back-projected and the virtual camera (DepthSensor) renders through it.
Eigen::Matrix3d CameraRotation(const CameraOptions& camera);

// Reads a 16-bit single-channel (greyscale) PNG. Other bit depths or colour types are
// refused naming the file and what it holds; so are images over 2^28 pixels.
Status ReadDepthPng(const std::string& path, RawDepthImage* image);
// Reads a mask of width by height pixels (any PNG, 8- or 16-bit, grey or colour; non-zero
// in any colour channel = keep). Errors name the file (and both sizes when they differ).
Status ReadMaskPng(const std::string& path, int width, int height, std::vector<uint8_t>* keep);
// Writes a 16-bit greyscale PNG, atomically (a temporary file renamed into place).
Status WriteDepthPng(const std::string& path, const RawDepthImage& image);
// Writes width * height keep flags as an 8-bit greyscale PNG (255 keep, 0 drop), atomically.
Status WriteMaskPng(const std::string& path, int width, int height, const std::vector<uint8_t>& keep);

// Back-projects every pixel with a depth (inside [min_depth, max_depth], kept by `keep`
// when given: width * height flags) through the camera into the scene frame:
// p = position + R^T z ((u - cx) / fx, (v - cy) / fy, 1). The image must be the camera's
// width by height. *sensor (may be null) receives the camera centre and orientation, the
// viewpoint for visibility and normal orientation.
Status BackProjectDepth(const RawDepthImage& image, const CameraOptions& camera,
                        const DepthImageOptions& options, const std::vector<uint8_t>* keep,
                        PointCloud* cloud, SensorPose* sensor = nullptr);

// ReadDepthPng, the frame's mask (options.mask_dir), BackProjectDepth. Errors name the
// file.
Status ReadDepthFrame(const std::string& path, const CameraOptions& camera,
                      const DepthImageOptions& options, PointCloud* cloud,
                      SensorPose* sensor = nullptr);

// The depth image a camera would store for these points: each point in front of the
// camera is projected to its nearest pixel centre and the nearest point per pixel kept,
// its depth rounded to depth_scale units. Points behind the camera, outside the image or
// beyond 65535 units are left out and counted in *dropped. The inverse of
// BackProjectDepth up to the rounding for points that lie on pixel rays (a depth
// camera's, e.g. femreg synth's).
RawDepthImage CloudToDepthImage(const PointCloud& cloud, const CameraOptions& camera,
                                double depth_scale, int* dropped = nullptr);

// Reads a frame by its extension: .png as a depth image (ReadDepthFrame, with the
// camera), anything else with ReadPointCloud. The frame front end of `femreg register`.
Status ReadFrame(const std::string& path, const CameraOptions& camera,
                 const DepthImageOptions& depth, PointCloud* cloud,
                 int* nonfinite_dropped = nullptr, SensorPose* sensor = nullptr);

}  // namespace femreg

#endif  // FEMREG_POINT_CLOUD_H_
