// femreg mesh SURFACE --out MESH: a closed triangle surface (PLY, OBJ, STL) tetrahedralized by
// TetGen, written in a format femreg reads, with a report of what was done.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "femreg/io.h"
#include "femreg/meshing.h"

namespace femreg {
namespace cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct MeshArgs {
  std::string surface;
  std::string out;
  MeshingOptions options;
  double scale = 1.0;
  bool single_region = false;
  bool no_remesh = false;
  bool force = false;
  bool json = false;
  int cage = 0;  // --cage N: a coarse cage of about N vertices around the surface (MakeCage)
};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string OutputFormat(const std::string& path) {
  const std::string ext = Lower(fs::path(path).extension().string());
  if (ext == ".vtu") return "VTU (VTK XML)";
  if (ext == ".msh") return "Gmsh 2.2 ASCII";
  if (ext == ".mesh") return "MEDIT";
  if (ext == ".vtk") return "VTK legacy ASCII";
  return "";
}

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string G(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

struct Timings {
  double read = 0.0, write = 0.0, total = 0.0;
};

std::string JsonReport(const MeshArgs& args, const MeshingReport& r, const Timings& t,
                       const std::string& error, const CageReport* cage = nullptr) {
  std::ostringstream os;
  os << "{\n  \"ok\": " << (error.empty() ? "true" : "false") << ",\n";
  if (!error.empty()) os << "  \"error\": " << JsonString(error) << ",\n";
  os << "  \"surface_file\": " << JsonString(args.surface) << ",\n"
     << "  \"out\": " << JsonString(args.out) << ",\n"
     << "  \"input\": {\"vertices\": " << r.input_vertices
     << ", \"triangles\": " << r.input_triangles << ", \"scale\": " << JsonNumber(args.scale)
     << "},\n"
     << "  \"wrapped\": ";
  if (r.wrapped) {
    os << "{\"alpha\": " << JsonNumber(r.wrap_alpha) << ", \"offset\": " << JsonNumber(r.wrap_offset)
       << ", \"vertices\": " << r.wrapped_vertices << ", \"triangles\": " << r.wrapped_triangles << "},\n";
  } else {
    os << "null,\n";
  }
  os << "  \"cleaning\": {\"merged_vertices\": " << r.merged_vertices
     << ", \"merge_distance\": " << JsonNumber(r.merge_distance)
     << ", \"unused_vertices\": " << r.unused_vertices << "},\n"
     << "  \"surface\": {\"vertices\": " << r.surface_vertices << ", \"shells\": " << r.shells
     << ", \"cavities\": " << r.cavities << ", \"area\": " << JsonNumber(r.surface_area)
     << ", \"volume\": " << JsonNumber(r.surface_volume)
     << ", \"mean_edge_length\": " << JsonNumber(r.surface_mean_edge_length) << "},\n"
     << "  \"remeshed\": ";
  if (r.remeshed) {
    os << "{\"vertices\": " << r.remeshed_vertices << ", \"triangles\": " << r.remeshed_triangles
       << ", \"sharp_edges\": " << r.sharp_edges
       << ", \"dropped_sharp_edges\": " << r.dropped_sharp_edges
       << ", \"corner_vertices\": " << r.corner_vertices << ", \"short_edges\": " << r.short_edges
       << ", \"volume\": " << JsonNumber(r.remeshed_volume)
       << ", \"mean_edge_length\": " << JsonNumber(r.remeshed_mean_edge_length) << "},\n";
  } else {
    os << "null,\n";
  }
  os << "  \"settings\": {\"edge_length\": " << JsonNumber(r.edge_length)
     << ", \"max_volume\": " << JsonNumber(r.max_volume)
     << ", \"radius_edge_ratio\": " << JsonNumber(r.radius_edge_ratio)
     << ", \"min_dihedral_deg\": " << JsonNumber(r.min_dihedral_deg)
     << ", \"keep_surface\": " << (args.options.keep_surface ? "true" : "false")
     << ", \"remesh\": " << (args.options.remesh ? "true" : "false")
     << ", \"feature_angle_deg\": " << JsonNumber(args.options.feature_angle_deg)
     << ", \"remesh_iterations\": " << args.options.remesh_iterations
     << ", \"tetgen_switches\": " << JsonString(r.tetgen_switches) << "},\n";
  if (error.empty()) {
    const MeshQuality& q = r.quality;
    os << "  \"mesh\": {\"vertices\": " << r.vertices << ", \"tetrahedra\": " << r.tets
       << ", \"regions\": " << r.regions << ", \"boundary_triangles\": " << r.boundary_triangles
       << ", \"volume\": " << JsonNumber(r.mesh_volume)
       << ",\n           \"edge_length\": {\"min\": " << JsonNumber(r.min_edge_length)
       << ", \"mean\": " << JsonNumber(r.mean_edge_length)
       << ", \"max\": " << JsonNumber(r.max_edge_length) << "},\n"
       << "           \"quality\": {\"min_dihedral_deg\": " << JsonNumber(q.min_dihedral_deg)
       << ", \"max_dihedral_deg\": " << JsonNumber(q.max_dihedral_deg)
       << ", \"max_aspect_ratio\": " << JsonNumber(q.max_aspect_ratio)
       << ", \"mean_aspect_ratio\": " << JsonNumber(q.mean_aspect_ratio)
       << ", \"share_below_10_deg\": " << JsonNumber(r.small_dihedral_share)
       << ", \"share_above_170_deg\": " << JsonNumber(r.large_dihedral_share) << "}},\n";
  }
  if (cage != nullptr && error.empty()) {
    os << "  \"cage\": {\"target_vertices\": " << args.cage << ", \"passes\": " << cage->passes
       << ", \"edge_length\": " << JsonNumber(cage->edge_length) << ", \"offset\": " << JsonNumber(cage->offset)
       << ", \"outside_before\": " << cage->outside_before
       << ", \"outside_max_before\": " << JsonNumber(cage->outside_max_before)
       << ", \"outside\": " << cage->outside_vertices << ", \"outside_max\": " << JsonNumber(cage->outside_max)
       << "},\n";
  }
  os << "  \"tetgen_warnings\": " << JsonString(r.tetgen_warnings) << ",\n"
     << "  \"tetgen_log\": " << JsonString(r.tetgen_log) << ",\n"
     << "  \"seconds\": {\"read\": " << JsonNumber(t.read)
     << ", \"wrap\": " << JsonNumber(r.wrap_seconds) << ", \"checks\": " << JsonNumber(r.check_seconds)
     << ", \"remesh\": " << JsonNumber(r.remesh_seconds)
     << ", \"tetgen\": " << JsonNumber(r.tetgen_seconds)
     << ", \"finish\": " << JsonNumber(r.finish_seconds) << ", \"write\": " << JsonNumber(t.write)
     << ", \"total\": " << JsonNumber(t.total) << "}\n}\n";
  return os.str();
}

std::string TextReport(const MeshArgs& args, const MeshingReport& r, const Timings& t) {
  const MeshQuality& q = r.quality;
  std::ostringstream os;
  os << "femreg mesh: " << args.surface << " -> " << args.out << "\n"
     << "input:     " << r.input_vertices << " vertices, " << r.input_triangles << " triangles";
  if (args.scale != 1.0) os << ", coordinates scaled by " << G(args.scale);
  os << "\n";
  if (r.wrapped) {
    os << "wrapped:   alpha " << G(r.wrap_alpha) << ", offset " << G(r.wrap_offset) << ": "
       << r.wrapped_vertices << " vertices, " << r.wrapped_triangles
       << " triangles, closed around the input (meshed in its place)\n";
  }
  os << "cleaned:   " << r.merged_vertices << " duplicate vertices merged (closer than "
     << G(r.merge_distance) << "), " << r.unused_vertices
     << " unused dropped: " << r.surface_vertices << " vertices\n"
     << "surface:   " << r.shells << " closed shell" << (r.shells == 1 ? "" : "s") << " ("
     << r.cavities << " cavit" << (r.cavities == 1 ? "y" : "ies") << "), area " << G(r.surface_area)
     << ", volume " << G(r.surface_volume) << ", mean edge " << G(r.surface_mean_edge_length)
     << "\n";
  if (r.remeshed) {
    os << "remeshed:  " << r.remeshed_vertices << " vertices, " << r.remeshed_triangles
       << " triangles, mean edge " << G(r.remeshed_mean_edge_length) << ", volume "
       << G(r.remeshed_volume) << "; " << r.sharp_edges << " sharp edges (over "
       << G(args.options.feature_angle_deg) << " deg) kept as feature lines ("
       << r.dropped_sharp_edges << " more in lines shorter than 2 L not), " << r.corner_vertices
       << " corners fixed";
    if (r.short_edges > 0) {
      os << "; " << r.short_edges << " edges below L/10 between feature lines remeshed around "
         << "without them";
    }
    os << "\n";
  }
  os << "settings:  edge length " << G(r.edge_length)
     << (args.options.edge_length > 0 ? ""
         : r.wrapped && !args.options.keep_surface ? " (ALPHA, the wrap's detail)"
                                                   : " (the surface's mean edge)")
     << ", max volume "
     << G(r.max_volume) << ", radius-edge ratio <= " << G(r.radius_edge_ratio);
  if (r.min_dihedral_deg > 0) os << ", dihedral >= " << G(r.min_dihedral_deg) << " deg";
  os << (args.options.keep_surface ? ", surface kept" : r.remeshed ? ", remeshed surface kept" : "")
     << "  (TetGen -" << r.tetgen_switches
     << ")\n"
     << "mesh:      " << r.vertices << " vertices, " << r.tets << " tetrahedra, " << r.regions
     << " region" << (r.regions == 1 ? "" : "s") << ", " << r.boundary_triangles
     << " boundary triangles\n"
     << "volume:    " << G(r.mesh_volume) << " (the surface encloses " << G(r.surface_volume)
     << "; relative difference "
     << G(std::abs(r.mesh_volume - r.surface_volume) / std::abs(r.surface_volume)) << ")\n"
     << "edges:     min " << G(r.min_edge_length) << ", mean " << G(r.mean_edge_length) << ", max "
     << G(r.max_edge_length) << " (target " << G(r.edge_length) << ")\n"
     << "quality:   dihedral angles " << G(q.min_dihedral_deg) << " .. " << G(q.max_dihedral_deg)
     << " deg, aspect ratio max " << G(q.max_aspect_ratio) << ", mean " << G(q.mean_aspect_ratio)
     << " (1 = regular); " << G(100.0 * r.small_dihedral_share) << "% of the tetrahedra below "
     << "10 deg, " << G(100.0 * r.large_dihedral_share) << "% above 170\n"
     << "time:      " << G(t.total) << " s (read " << G(t.read)
     << (r.wrapped ? ", wrap " + G(r.wrap_seconds) : std::string()) << ", checks " << G(r.check_seconds)
     << ", remesh " << G(r.remesh_seconds)
     << ", TetGen " << G(r.tetgen_seconds) << ", finish " << G(r.finish_seconds) << ", write "
     << G(t.write) << ")\n";
  if (!r.tetgen_warnings.empty()) os << "TetGen warns:\n" << r.tetgen_warnings;
  os << "wrote:     " << args.out << " (" << OutputFormat(args.out) << ")\n";
  return os.str();
}

int RunMesh(MeshArgs args) {
  const Clock::time_point start = Clock::now();
  Timings timings;
  MeshingReport report;
  auto fail = [&](const std::string& message) {
    timings.total = Since(start);
    std::cerr << "femreg mesh: " << message << "\n";
    if (args.json) std::cout << JsonReport(args, report, timings, message);
    return 1;
  };
  if (OutputFormat(args.out).empty()) {
    return fail(args.out + ": unknown mesh format '" + fs::path(args.out).extension().string() +
                "' (expected .vtu, .msh, .mesh or .vtk)");
  }
  std::error_code ec;
  if (fs::exists(args.out, ec) && !args.force) {
    return fail(args.out + ": exists; pass --force to overwrite it");
  }
  args.options.region_per_shell = !args.single_region;
  args.options.remesh = !args.no_remesh;
  std::string error;
  if (!args.options.IsValid(&error)) return fail("bad option: " + error);

  Vertices V;
  Triangles F;
  Status status = ReadSurface(args.surface, &V, &F);
  timings.read = Since(start);
  if (!status.ok()) return fail(status.message());
  V *= args.scale;

  TetMesh mesh;
  CageReport cage;
  if (args.cage > 0) {
    if (args.options.edge_length > 0 || args.options.keep_surface || args.no_remesh) {
      return fail("--cage chooses the edge length and remeshes: it does not combine with --edge-length, "
                  "--keep-surface or --no-remesh");
    }
    status = MakeCage(V, F, args.cage, args.options, &mesh, &cage, args.surface);
    report = cage.meshing;
  } else {
    status = TetrahedralizeSurface(V, F, args.options, &mesh, &report, args.surface);
  }
  if (!status.ok()) return fail(status.message());
  if (args.cage > 0) {
    // The move changed the mesh after TetGen's report: its counts stand, its measures follow.
    report.mesh_volume = RestVolume(mesh);
  }

  const Clock::time_point write_start = Clock::now();
  status = WriteTetMesh(args.out, mesh);
  timings.write = Since(write_start);
  if (!status.ok()) return fail(status.message());
  timings.total = Since(start);
  std::cout << (args.json ? JsonReport(args, report, timings, "", args.cage > 0 ? &cage : nullptr)
                          : TextReport(args, report, timings));
  if (args.cage > 0 && !args.json) {
    std::cout << "cage:      " << mesh.num_vertices() << " vertices for a target of " << args.cage << " ("
              << cage.passes << " pass" << (cage.passes == 1 ? "" : "es") << ", edge length "
              << G(cage.edge_length) << "); boundary moved out by " << G(cage.offset) << "; "
              << cage.outside_before << " surface vertices were outside (farthest "
              << G(cage.outside_max_before) << "), " << cage.outside_vertices << " still are (farthest "
              << G(cage.outside_max) << ")\n";
  }
  return 0;
}

}  // namespace

void AddMeshCommand(CLI::App* app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app->add_subcommand(
      "mesh",
      "Tetrahedralize the solid bounded by a closed triangle surface (a scan, a CAD export) "
      "with TetGen, after remeshing the surface to --edge-length with CGAL, and write the "
      "tetrahedral mesh.\n"
      "The surface is checked first: duplicate vertices are merged; an open surface (boundary "
      "edges), edges in more than two triangles, vertices where sheets meet, inconsistently "
      "oriented neighbours, zero-area triangles, triangles that cross or touch, or a shell "
      "with no volume are refused with a message that says where. Several closed shells are "
      "fine: disjoint ones become separate regions, nested ones cavities. A surface refused so "
      "(a raw scan) can be wrapped first with --wrap ALPHA: a closed surface around it, "
      "meshed in its place.");
  cmd->footer(
      "Units: whatever the surface file uses, times --scale (femreg works in metres: a scan "
      "in millimetres wants --scale 0.001). The lengths and volumes of the options are in those "
      "units.\n"
      "With --edge-length L the surface is first remeshed to edges of about L (CGAL's "
      "isotropic remeshing: edges split, collapsed and flipped, vertices smoothed and put back "
      "on the input surface; edges sharper than --feature-angle stay as feature lines, their "
      "corners in place), checked again, and TetGen fills it without changing it: the mean "
      "edge comes out near L and the vertex count follows L, on a scan finer or coarser than L. "
      "The remeshed surface's vertices are on the input, its triangles cut chords across "
      "its curvature: the volume changes a little (reported; more where L is large against "
      "the curvature). With --no-remesh, or without --edge-length, TetGen gets the input "
      "surface: it does not coarsen it (near a surface finer than L the elements are as fine "
      "as it) and, without --keep-surface, may split its triangles for quality and size.\n"
      "The elements are written in a spatial order (along a Morton curve through their "
      "centroids), so that registration's loops over them read and write memory close "
      "together.\n"
      "Prints the input and output counts, merged duplicate vertices, the volume of the surface "
      "and "
      "of the mesh, edge lengths, element quality (dihedral angles, aspect ratio) and times.\n"
      "Exit code 0 on success; 2 for a wrong or missing argument (a file that does not exist); 1 when the surface cannot be read or meshed, the output "
      "exists (without --force) or cannot be written (the reason goes to stderr; nothing is "
      "written then). The output is written to a temporary file and renamed.\n"
      "Example: femreg mesh scan.stl --out scan.vtu --scale 0.001 --edge-length 0.004");
  cmd->footer(cmd->get_footer() +
              "\nThe report's quality line gives the dihedral angles' range and the share of "
              "tetrahedra with an angle below 10 or above 170 degrees (slivers).");
  cmd->add_option("surface", args->surface,
                  "Closed triangle surface: .ply (ASCII or binary), "
                  ".obj or .stl (ASCII or binary)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out,-o", args->out,
                  "Tetrahedral mesh to write; the format by its extension: .vtu (VTK XML), .msh "
                  "(Gmsh 2.2), .mesh (MEDIT) or .vtk (VTK legacy)")
      ->required();
  cmd->add_option("--edge-length,-l", args->options.edge_length,
                  "Target edge length of the tetrahedra, in the scaled units; the surface is "
                  "remeshed to it first unless --no-remesh or --keep-surface (default: the "
                  "surface's mean edge length, surface as it is)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--quality,-q", args->options.radius_edge_ratio,
                  "Largest circumradius-to-shortest-edge ratio of a tetrahedron (>= 1.1; smaller "
                  "is rounder and makes more elements; TetGen's own default is 2)")
      ->capture_default_str()
      ->check(CLI::Range(1.1, 100.0));
  cmd->add_option("--min-dihedral", args->options.min_dihedral_deg,
                  "Smallest dihedral angle to aim for, degrees (0 to 18; 0: no bound; elements "
                  "on the surface keep the angles its triangles force)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 18.0));
  cmd->add_option(
         "--max-volume", args->options.max_volume,
         "Largest tetrahedron volume, in the scaled units cubed (default: L^3 / (4 sqrt 2) "
         "for the edge length L, which makes the mean edge about L inside a large solid; "
         "the smaller bound applies when both are given)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--scale", args->scale,
                  "Multiply the surface's coordinates by S first (0.001: millimetres to metres)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--merge-distance", args->options.merge_distance,
                  "Merge vertices closer than this, in the scaled units (default: 1e-9 of the "
                  "bounding box diagonal; 0: exact copies only)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--time-limit", args->options.time_limit_seconds,
                  "Stop TetGen after this many seconds (default: no limit)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--keep-surface", args->options.keep_surface,
                "Keep the surface triangles as they are (no remeshing, no point added on the "
                "surface): the mesh's boundary is the input surface");
  cmd->add_flag("--no-remesh", args->no_remesh,
                "Give TetGen the input surface, not one remeshed to --edge-length (the "
                "behaviour before remeshing: a surface finer than L stays as fine)");
  cmd->add_option("--feature-angle", args->options.feature_angle_deg,
                  "When remeshing, edges where the surface's normal turns by more than this "
                  "(degrees) are kept as feature lines (a box's edges, a flat base's rim); "
                  "180: none")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 180.0));
  cmd->add_option("--remesh-iterations", args->options.remesh_iterations,
                  "Rounds of remeshing (split, collapse, flip, smooth)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  CLI::Option* wrap = cmd->add_option("--wrap", args->options.wrap,
                  "First replace the surface by its alpha wrap (CGAL's 3D Alpha Wrapping) at this "
                  "alpha, in the scaled units: a closed, manifold surface without crossings around "
                  "the input, for a scan or an export the checks refuse (holes, crossing or "
                  "duplicated triangles, non-manifold edges). Gaps, holes and openings narrower "
                  "than about ALPHA close, details finer than it are smoothed away: about the "
                  "narrowest part to keep. Without --edge-length the wrap is meshed at L = ALPHA "
                  "(default: no wrap)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--wrap-offset", args->options.wrap_offset,
                  "How far outside the input the wrap lies, in the scaled units (default: ALPHA / 30)")
      ->check(CLI::PositiveNumber)
      ->needs(wrap);
  cmd->add_flag("--single-region", args->single_region,
                "Put every element in region 0 (default: one region per closed shell)");
  cmd->add_option("--cage", args->cage,
                  "Make a coarse cage of about N vertices that encloses the surface, to carry it "
                  "as an embedded surface (objects[i].surface): the edge length is chosen for N "
                  "and the boundary moved out until every surface vertex is inside")
      ->check(CLI::Range(8, 10000000));
  cmd->add_flag("--force", args->force, "Overwrite MESH if it exists");
  cmd->add_flag("--json", args->json, "Print one JSON object instead of text");
  cmd->callback([args] { SetExitCode(RunMesh(*args)); });
}

}  // namespace cli
}  // namespace femreg
