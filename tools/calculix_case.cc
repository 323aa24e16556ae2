// femreg_calculix_case: the two halves of a calibration test case made with CalculiX
// (tools/make_calculix_sag.sh runs them around ccx).
//
//   femreg_calculix_case deck SCENE OUT.inp E=...
//       object 0 of SCENE (its mesh as C3D4, its clamps, gravity and nodal loads, density and
//       nu) with Young's modulus E as a CalculiX NLGEOM deck. Only clamps (no prescribed
//       displacements) are written.
//   femreg_calculix_case clouds SCENE CCX.dat OUT_DIR [seed=1] [samples=4000]
//       reads the last displacement block of CCX.dat, and writes into OUT_DIR:
//       calculix_u.csv   per vertex of the scene's mesh: rest and CalculiX displacement
//       surface.pcd      noise-free points sampled uniformly (by area) on the deformed surface
//       camera.pcd       the deformed surface rendered by the scene's registration.camera
//                        with the virtual sensor's noise (sigma = 2.85e-3 z^2)
//       calculix.vtu     the deformed mesh, for ParaView
#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace {

using namespace femreg;

int Usage() {
  std::cerr << "usage: femreg_calculix_case deck SCENE OUT.inp E=VALUE\n"
               "       femreg_calculix_case clouds SCENE CCX.dat OUT_DIR [seed=1] [samples=4000]\n";
  return 2;
}

double KeyValue(int argc, char** argv, int first, const std::string& key, double fallback) {
  for (int i = first; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind(key + "=", 0) == 0) return std::stod(a.substr(key.size() + 1));
  }
  return fallback;
}

bool Load(const std::string& path, Scene* scene, TetMesh* mesh, ForwardProblem* problem) {
  Status s = LoadScene(path, scene);
  if (s.ok()) s = LoadObjectMesh(*scene, 0, mesh);
  if (s.ok()) s = BuildForwardProblem(*scene, 0, *mesh, problem);
  if (!s.ok()) std::cerr << "femreg_calculix_case: " << s.message() << "\n";
  return s.ok();
}

int Deck(int argc, char** argv) {
  if (argc < 5) return Usage();
  Scene scene;
  TetMesh mesh;
  ForwardProblem problem;
  if (!Load(argv[2], &scene, &mesh, &problem)) return 1;
  const Material& m = scene.objects[0].material;
  const double E = KeyValue(argc, argv, 4, "E", m.youngs_modulus);
  if (!problem.prescribed.empty()) {
    std::cerr << "femreg_calculix_case: prescribed displacements are not written\n";
    return 1;
  }
  std::ofstream out(argv[3]);
  out.precision(17);
  out << "** femreg_calculix_case: " << argv[2] << ", " << mesh.num_vertices() << " nodes, "
      << mesh.num_tets() << " C3D4, E = " << E << "\n*NODE, NSET=Nall\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out << v + 1 << ", " << mesh.rest(v, 0) << ", " << mesh.rest(v, 1) << ", " << mesh.rest(v, 2) << "\n";
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=Eall\n";
  for (int t = 0; t < mesh.num_tets(); ++t) {
    out << t + 1 << ", " << mesh.tets(t, 0) + 1 << ", " << mesh.tets(t, 1) + 1 << ", "
        << mesh.tets(t, 2) + 1 << ", " << mesh.tets(t, 3) + 1 << "\n";
  }
  out << "*NSET, NSET=Nclamp\n";
  for (size_t i = 0; i < problem.clamped.size(); ++i) {
    out << problem.clamped[i] + 1 << (i % 10 == 9 || i + 1 == problem.clamped.size() ? "\n" : ", ");
  }
  out << "*BOUNDARY\nNclamp, 1, 3\n*MATERIAL, NAME=M\n*ELASTIC\n" << E << ", " << m.poisson_ratio
      << "\n*DENSITY\n" << m.density << "\n*SOLID SECTION, ELSET=Eall, MATERIAL=M\n"
      << "*STEP, NLGEOM, INC=1000\n*STATIC\n0.05, 1.0, 1e-6, 0.1\n";
  if (!problem.nodal_loads.empty()) {
    out << "*CLOAD\n";
    for (const auto& [v, f] : problem.nodal_loads) {
      for (int i = 0; i < 3; ++i) {
        if (f(i) != 0) out << v + 1 << ", " << i + 1 << ", " << f(i) << "\n";
      }
    }
  }
  const double g = problem.gravity.norm();
  if (g > 0) {
    const Eigen::Vector3d d = problem.gravity / g;
    out << "*DLOAD\nEall, GRAV, " << g << ", " << d(0) << ", " << d(1) << ", " << d(2) << "\n";
  }
  out << "*NODE PRINT, NSET=Nall\nU\n*END STEP\n";
  return out ? 0 : 1;
}

// The last "displacements" block of a CalculiX .dat file: node -> u.
bool ReadDat(const std::string& path, int nodes, Vertices* u) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::map<int, Eigen::Vector3d>> blocks;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.find("displacements") != std::string::npos) {
      blocks.emplace_back();
      inside = true;
      continue;
    }
    if (!inside) continue;
    std::istringstream is(line);
    int id;
    Eigen::Vector3d d;
    if (is >> id >> d(0) >> d(1) >> d(2)) {
      blocks.back()[id] = d;
    } else if (line.find_first_not_of(" \t\r") != std::string::npos) {
      inside = false;
    }
  }
  if (blocks.empty() || static_cast<int>(blocks.back().size()) != nodes) {
    std::cerr << "femreg_calculix_case: " << path << ": no displacement block with " << nodes
              << " nodes\n";
    return false;
  }
  u->resize(nodes, 3);
  for (const auto& [id, d] : blocks.back()) u->row(id - 1) = d.transpose();
  return true;
}

int Clouds(int argc, char** argv) {
  if (argc < 5) return Usage();
  Scene scene;
  TetMesh mesh;
  ForwardProblem problem;
  if (!Load(argv[2], &scene, &mesh, &problem)) return 1;
  Vertices u;
  if (!ReadDat(argv[3], mesh.num_vertices(), &u)) return 1;
  const std::string dir = argv[4];
  const uint64_t seed = static_cast<uint64_t>(KeyValue(argc, argv, 5, "seed", 1));
  const int samples = static_cast<int>(KeyValue(argc, argv, 5, "samples", 4000));
  mesh.x = mesh.rest + u;

  std::ofstream csv(dir + "/calculix_u.csv");
  csv.precision(17);
  csv << "vertex,X,Y,Z,ux,uy,uz\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    csv << v << "," << mesh.rest(v, 0) << "," << mesh.rest(v, 1) << "," << mesh.rest(v, 2) << ","
        << u(v, 0) << "," << u(v, 1) << "," << u(v, 2) << "\n";
  }

  // Noise-free: points uniform by area on the deformed surface triangles.
  std::vector<double> cumulative;
  double area = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = mesh.x.row(mesh.surface(f, 0)), b = mesh.x.row(mesh.surface(f, 1)),
                          c = mesh.x.row(mesh.surface(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
    cumulative.push_back(area);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  PointCloud surface;
  surface.points.resize(samples, 3);
  for (int i = 0; i < samples; ++i) {
    const double r = uniform(rng) * area;
    const int f = static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(), r) -
                                   cumulative.begin());
    double s = uniform(rng), t = uniform(rng);
    if (s + t > 1) {
      s = 1 - s;
      t = 1 - t;
    }
    const Eigen::Vector3d a = mesh.x.row(mesh.surface(f, 0)), b = mesh.x.row(mesh.surface(f, 1)),
                          c = mesh.x.row(mesh.surface(f, 2));
    surface.points.row(i) = (a + s * (b - a) + t * (c - a)).transpose();
  }
  Status status = WritePointCloud(dir + "/surface.pcd", surface);

  // The virtual camera with its noise.
  DepthSensorOptions sensor;
  sensor.camera = scene.registration.camera;
  if (!sensor.camera.enabled) {
    std::cerr << "femreg_calculix_case: the scene has no registration.camera\n";
    return 1;
  }
  DepthSensor camera(sensor);
  std::vector<RenderSurface> surfaces = {{&mesh.x, &mesh.surface, true}};
  const PointCloud seen = camera.Sample(camera.Render(surfaces), surfaces, seed);
  if (status.ok()) status = WritePointCloud(dir + "/camera.pcd", seen);
  if (status.ok()) status = WriteVtu(dir + "/calculix.vtu", mesh, mesh.x, {});
  if (!status.ok()) {
    std::cerr << "femreg_calculix_case: " << status.message() << "\n";
    return 1;
  }
  std::printf("%d vertices, max |u| %.6g m; surface.pcd %d points, camera.pcd %d points\n",
              mesh.num_vertices(), u.rowwise().norm().maxCoeff(), surface.size(), seen.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return Usage();
  const std::string mode = argv[1];
  if (mode == "deck") return Deck(argc, argv);
  if (mode == "clouds") return Clouds(argc, argv);
  return Usage();
}
