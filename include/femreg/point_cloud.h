// femreg/point_cloud.h - reading, writing and preprocessing point clouds.
#ifndef FEMREG_POINT_CLOUD_H_
#define FEMREG_POINT_CLOUD_H_

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "femreg/camera_io.h"
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

// Writes a binary PCD (with normals when the cloud has them), atomically; a path that does
// not end in .pcd is refused.
Status WritePointCloud(const std::string& path, const PointCloud& cloud);

// The plane preprocess.plane removed from a cloud: normal . x = offset (|normal| = 1), and
// the points it removed. Empty (no points) when no plane was removed.
struct RemovedPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double offset = 0.0;
  Eigen::Matrix<double, Eigen::Dynamic, 3> points;
};

// Drops non-finite points (counted), then crops, removes the dominant plane (into *plane
// when given), voxel-downsamples, removes statistical outliers and estimates normals as the
// options ask (oriented towards `viewpoint`, the camera centre).
void PreprocessPointCloud(const PreprocessOptions& options, PointCloud* cloud,
                          int* nonfinite_dropped = nullptr,
                          const Eigen::Vector3d& viewpoint = Eigen::Vector3d::Zero(),
                          RemovedPlane* plane = nullptr);

// The cloud as Tracker::Track fits it, before its automatic subsampling (auto_voxel): the
// input transform of options.preprocess (scale, rotation, translation), the flying pixels
// removed (preprocess.flying_pixels, counted in *flying_pixels), then PreprocessPointCloud oriented towards the camera centre (registration.camera), else the
// cloud's VIEWPOINT. The tracker's own path; `femreg register` writes the result beside the
// meshes and checks its units on it.
void PrepareCloudForTracking(const RegistrationOptions& options, PointCloud* cloud,
                             int* nonfinite_dropped = nullptr, int* flying_pixels = nullptr,
                             RemovedPlane* plane = nullptr);

// Removes points with a non-finite coordinate (or normal); returns how many.
int DropNonFinite(PointCloud* cloud);

// ---------------------------------------------------------------------------------------
// Depth images (depth_image.cc): a frame from a depth camera whose pixels are depths along
// the optical axis, as a 16-bit PNG or a uint16 .npy in units of depth_scale (millimetres
// by default, the common sensor convention; TUM RGB-D's 5000 per metre), or a float .npy in
// metres; 0 where the sensor saw nothing. The files are femreg/camera_io.h's. The camera's
// intrinsics and pose are the scene's (CameraOptions: pixel centres at integer coordinates,
// x right, y down, z forward, as the virtual camera of femreg/synth.h).

struct DepthImageOptions {
  double depth_scale = 0.001;  // metres per depth unit (> 0); 0.001: millimetres. Images in metres ignore it
  double min_depth = 0.0;      // m; pixels closer are dropped
  double max_depth = 0.0;      // m; pixels farther are dropped; 0 = no limit
  int pixel_stride = 1;        // back-project every k-th pixel in u and v (>= 1)
  // A folder of masks (PNG, any bit depth or colour; non-zero = keep the pixel) named like
  // the depth frames (MaskPathFor); empty: no masks. A frame whose mask is missing is an
  // error.
  std::string mask_dir;
  bool IsValid(std::string* error) const;  // names the field
};

// The camera's rotation, world to camera (rows: the image's x, y and optical axes):
// p_camera = R (p - camera.position). The one construction of the camera frame: depth
// images are back-projected and the virtual camera (DepthSensor) renders through it.
Eigen::Matrix3d CameraRotation(const CameraOptions& camera);

// Sets the camera's intrinsics from a file: fx, fy, cx, cy, width and height from an Open3D
// PinholeCameraIntrinsic JSON (ReadOpen3dIntrinsics); fx, fy, cx and cy from a matrix as
// text (ReadMatrixIntrinsics: any file that is not JSON), whose width and height stay the
// camera's. Its pose and `enabled` stay as they are. Errors name the file and the field.
Status ReadCameraIntrinsics(const std::string& path, CameraOptions* camera);
// Writes the camera's intrinsics as that JSON (WriteOpen3dIntrinsics).
Status WriteCameraIntrinsics(const std::string& path, const CameraOptions& camera);
// The camera's intrinsics, and a camera given them (its pose and `enabled` kept).
PinholeIntrinsics IntrinsicsOf(const CameraOptions& camera);
void SetIntrinsics(const PinholeIntrinsics& intrinsics, CameraOptions* camera);

// Back-projects every pixel with a depth (inside [min_depth, max_depth], kept by `keep`
// when given: width * height flags) through the camera into the scene frame:
// p = position + R^T z ((u - cx) / fx, (v - cy) / fy, 1), z = units * depth_scale, or the
// image's metres. The image must be the camera's width by height. *sensor (may be null)
// receives the camera centre and orientation, the viewpoint for visibility and normal
// orientation.
Status BackProjectDepth(const RawDepthImage& image, const CameraOptions& camera,
                        const DepthImageOptions& options, const std::vector<uint8_t>* keep,
                        PointCloud* cloud, SensorPose* sensor = nullptr);

// A depth frame from its file: a .npy or a .png (ReadDepthImageFile); its mask
// (options.mask_dir, MaskPathFor); BackProjectDepth. Errors name the file.
Status ReadDepthFrame(const std::string& path, const CameraOptions& camera,
                      const DepthImageOptions& options, PointCloud* cloud,
                      SensorPose* sensor = nullptr);

// The mask of depth frame `frame` in `mask_dir`: the frame's file name for a PNG
// (masks/frame_0007.png for depth/frame_0007.png), its stem and .png for a .npy.
std::string MaskPathFor(const std::string& mask_dir, const std::string& frame);

// The depth image a camera would store for these points: each point in front of the
// camera is projected to its nearest pixel centre and the nearest point per pixel kept,
// its depth rounded to depth_scale units. Points behind the camera, outside the image or
// beyond 65535 units are left out and counted in *dropped. The inverse of
// BackProjectDepth up to the rounding for points that lie on pixel rays (a depth
// camera's, e.g. femreg synth's).
RawDepthImage CloudToDepthImage(const PointCloud& cloud, const CameraOptions& camera,
                                double depth_scale, int* dropped = nullptr);

// True for a depth-image frame's extension (.png, .npy; any case).
bool IsDepthImageFile(const std::string& path);

// Reads a frame by its extension: .png and .npy as depth images (ReadDepthFrame, with the
// camera), anything else with ReadPointCloud. The frame front end of `femreg register`.
Status ReadFrame(const std::string& path, const CameraOptions& camera,
                 const DepthImageOptions& depth, PointCloud* cloud,
                 int* nonfinite_dropped = nullptr, SensorPose* sensor = nullptr);

// The frames of a recording, in order.
struct FrameFiles {
  std::vector<std::string> files;
  std::string tum_list;      // the TUM RGB-D list they come from; "" otherwise
  double depth_scale = 0.0;  // metres per depth unit the layout prescribes (TUM: 1/5000); 0: none
  std::vector<double> times;  // each frame's timestamp (s) from a TUM list; empty otherwise
};

// What `femreg register --frames PATH` reads. PATH is one of:
//  - a TUM RGB-D sequence: a folder with an associations file or depth.txt (FindTumList),
//    or such a list itself: its depth images in the list's order (ReadTumSequence), with
//    depth_scale kTumDepthScale;
//  - a folder: its frames (.pcd, .ply, .xyz, .txt, .png, .npy) in natural order of names;
//  - a glob pattern: its matches in natural order.
// Errors name the folder, the pattern, or the list and its line.
Status ListFrameFiles(const std::string& path, FrameFiles* frames);

}  // namespace femreg

#endif  // FEMREG_POINT_CLOUD_H_
